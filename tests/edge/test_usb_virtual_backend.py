"""The virtual board through the real pyusb code path (a custom usb.backend.IBackend)."""

from __future__ import annotations

import errno
import threading
import time

import pytest
import usb.core
import usb.util

from edge.sources.usb_virtual import DEFAULT_PID, DEFAULT_VID, EP_IN, EP_OUT, VirtualUsbBackend
from firmware_protocol import codec
from firmware_protocol.virtual_board import VirtualBoard

pytestmark = pytest.mark.timeout(30)


def cmd(name, seq=1, **fields):
    return codec.encode_command(name, seq, **fields)


@pytest.fixture
def backend():
    return VirtualUsbBackend(VirtualBoard(rows=16, cols=16, device_id="carpet-usb-01"))


def find(backend, **kw):
    return usb.core.find(idVendor=DEFAULT_VID, idProduct=DEFAULT_PID, backend=backend, **kw)


def read_for(dev, seconds, dec, size=4096):
    """Read the IN endpoint for ``seconds``, feeding ``dec``; returns the packets."""
    out = []
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        try:
            out += dec.feed(bytes(dev.read(EP_IN, size, timeout=50)))
        except usb.core.USBTimeoutError:
            pass
    return out


def test_find_and_descriptors_through_pyusb(backend):
    dev = find(backend)
    assert dev is not None
    assert (dev.idVendor, dev.idProduct, dev.bDeviceClass) == (0x1209, 0xCA7A, 0xFF)
    assert dev.serial_number == "carpet-usb-01"
    assert dev.manufacturer == "CAvatar" and "carpet" in dev.product
    assert usb.util.get_string(dev, dev.iSerialNumber) == "carpet-usb-01"
    cfg = dev.get_active_configuration()
    intf = cfg[(0, 0)]
    assert intf.bInterfaceClass == 0xFF
    eps = {e.bEndpointAddress: e for e in intf}
    assert set(eps) == {EP_OUT, EP_IN}
    assert all(usb.util.endpoint_type(e.bmAttributes) == usb.util.ENDPOINT_TYPE_BULK for e in eps.values())
    assert eps[EP_IN].wMaxPacketSize == 64
    assert usb.core.find(idVendor=0x1234, backend=backend) is None
    assert len(list(usb.core.find(find_all=True, bDeviceClass=0xFF, backend=backend))) == 1
    assert "CAvatar" in str(dev)  # pyusb can print the whole descriptor tree


def test_vid_pid_are_configurable():
    backend = VirtualUsbBackend(VirtualBoard(rows=8, cols=8), vid=0xCAFE, pid=0x0001)
    assert find(backend) is None
    assert usb.core.find(idVendor=0xCAFE, idProduct=0x0001, backend=backend) is not None


def test_info_and_frames_over_bulk_endpoints(backend):
    dev = find(backend)
    dev.set_configuration()
    dec = codec.StreamDecoder()
    assert dev.write(EP_OUT, cmd("GET_INFO", 0) + cmd("START", 1)) > 0
    pkts = read_for(dev, 0.4, dec)
    infos = [p for p in pkts if isinstance(p, codec.Info)]
    assert infos and infos[-1].rows == 16 and infos[-1].device_id == "carpet-usb-01"
    codec.check_compatible(infos[-1])
    assert any(isinstance(p, codec.Ack) and p.cmd_seq == 1 for p in pkts)
    ends = [p for p in pkts if isinstance(p, codec.FrameEnd)]
    assert len(ends) >= 4  # 14 Hz for 0.4 s
    rows = [p for p in pkts if isinstance(p, codec.Row) and p.frame_seq == ends[0].frame_seq]
    assert len(rows) == 16
    crc = codec.frame_crc32(
        b"".join(v.to_bytes(2, "little") for v in codec.unpack_samples(r.samples, r.packing, r.count)) for r in rows
    )
    assert crc == ends[0].frame_crc32
    assert dec.stats.missed == 0 and not dec.stats.dropped


def test_read_timeout_raises_usbtimeouterror_with_etimedout(backend):
    dev = find(backend)
    dev.set_configuration()
    dev.read(EP_IN, 4096, timeout=100)  # the power-up INFO
    t0 = time.monotonic()
    with pytest.raises(usb.core.USBTimeoutError) as exc:
        dev.read(EP_IN, 4096, timeout=150)  # not streaming: nothing comes
    waited = time.monotonic() - t0
    assert exc.value.errno == errno.ETIMEDOUT and exc.value.backend_error_code == -7
    assert 0.14 <= waited < 1.0
    assert backend.counters["timeouts"] == 1


def test_a_read_waits_for_data_that_comes_before_the_timeout(backend):
    dev = find(backend)
    dev.read(EP_IN, 4096, timeout=100)
    threading.Timer(0.1, lambda: dev.write(EP_OUT, cmd("PING", 3, token=99))).start()
    t0 = time.monotonic()
    pkts = codec.StreamDecoder().feed(bytes(dev.read(EP_IN, 4096, timeout=2000)))
    assert 0.05 < time.monotonic() - t0 < 1.0
    assert pkts[0].NAME == "ACK" and pkts[0].value == 99


def test_reads_come_in_whole_usb_packets(backend):
    dev = find(backend)
    dev.write(EP_OUT, cmd("START", 1))
    time.sleep(0.1)  # several rows queued
    assert len(dev.read(EP_IN, 128, timeout=100)) == 128  # two full 64-byte packets
    with pytest.raises(usb.core.USBError) as exc:
        dev.read(EP_IN, 100, timeout=100)  # 64 + 36: the second packet does not fit
    assert exc.value.errno == errno.EOVERFLOW


def test_unplug_raises_enodev_and_replug_enumerates_again(backend):
    dev = find(backend)
    dev.set_configuration()
    dev.write(EP_OUT, cmd("START", 1))
    assert read_for(dev, 0.2, codec.StreamDecoder())
    address = dev.address
    backend.unplug()
    with pytest.raises(usb.core.USBError) as exc:
        dev.read(EP_IN, 4096, timeout=100)
    assert exc.value.errno == errno.ENODEV == 19
    with pytest.raises(usb.core.USBError) as exc:
        dev.write(EP_OUT, cmd("STOP", 2))
    assert exc.value.errno == errno.ENODEV
    assert find(backend) is None
    usb.util.dispose_resources(dev)  # must not raise on a vanished device

    backend.replug()
    with pytest.raises(usb.core.USBError) as exc:  # the old handle stays dead, as with libusb
        dev.read(EP_IN, 4096, timeout=100)
    assert exc.value.errno == errno.ENODEV
    dev2 = find(backend)
    assert dev2 is not None and dev2.address != address
    dec = codec.StreamDecoder()
    dev2.write(EP_OUT, cmd("GET_INFO", 0) + cmd("START", 1))
    pkts = read_for(dev2, 0.3, dec)
    assert isinstance(pkts[0], codec.Info)  # it booted again
    assert any(isinstance(p, codec.FrameEnd) for p in pkts)


def test_unplug_while_a_read_waits_ends_it_with_enodev(backend):
    dev = find(backend)
    dev.read(EP_IN, 4096, timeout=100)
    threading.Timer(0.1, backend.board.unplug).start()  # the board's own flag is obeyed too
    t0 = time.monotonic()
    with pytest.raises(usb.core.USBError) as exc:
        dev.read(EP_IN, 4096, timeout=5000)
    assert exc.value.errno == errno.ENODEV and time.monotonic() - t0 < 1.0


def test_faults_show_up_through_usb(backend):
    dev = find(backend)
    dec = codec.StreamDecoder()
    dev.write(EP_OUT, cmd("START", 1))
    read_for(dev, 0.1, dec)
    backend.board.flip_bits(5)
    backend.board.tear_next_frame()
    read_for(dev, 0.3, dec)
    assert sum(dec.stats.dropped.values()) >= 1 and dec.stats.missed >= 2
    assert backend.board.injected["flipped_bits"] == 5 and backend.board.injected["torn_rows"] == 2


def test_string_descriptor_zero_lists_en_us(backend):
    dev = find(backend)
    assert dev.langids == (0x0409,)
    with pytest.raises(usb.core.USBError) as exc:
        dev.ctrl_transfer(0xC0, 0x01, 0, 0, 8)  # a vendor request: the device stalls it
    assert exc.value.errno == errno.EPIPE
