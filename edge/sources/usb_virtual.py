"""A fake USB carpet board for pyusb: a ``usb.backend.IBackend`` around a :class:`VirtualBoard`.

The host code under test uses the real pyusb API (``usb.core.find``, descriptors,
``set_configuration``, ``write``/``read``, string descriptors, errors); only the
bottom layer, where libusb would be, is replaced. The device it shows::

    device   VID:PID 1209:CA7A (our default, configurable; 1209 is pid.codes' open-source VID),
             class 0xFF (vendor), USB 2.0 full speed, bcdDevice = firmware version,
             strings: 1 manufacturer, 2 product, 3 serial number = the board's device_id
    config 1 ── interface 0, class 0xFF ── bulk OUT 0x01 (64 B): commands → board.receive
                                        └─ bulk IN  0x81 (64 B): board.read(now) → host

Transfers behave as libusb's do: a bulk IN read returns what the device has queued (up
to the buffer), waits for data up to ``timeout`` ms (0 = forever) and then raises
``usb.core.USBTimeoutError`` (errno ETIMEDOUT); a buffer that is not a multiple of
wMaxPacketSize and cannot hold the next USB packet raises ``USBError`` (EOVERFLOW), so
read in multiples of 64. After ``unplug()`` every transfer on an open handle raises
``USBError`` with errno ENODEV (19) and ``find`` no longer lists the device; after
``replug()`` it enumerates again at a new address and must be found and opened again
(old handles stay dead, as with libusb). A bus-powered board boots again on replug.

Usage::

    import usb.core
    from firmware_protocol import codec
    from firmware_protocol.virtual_board import VirtualBoard
    from edge.sources.usb_virtual import VirtualUsbBackend

    backend = VirtualUsbBackend(VirtualBoard(rows=32, cols=32, device_id="carpet-01"))
    dev = usb.core.find(idVendor=0x1209, idProduct=0xCA7A, backend=backend)
    dev.set_configuration()
    dev.write(0x01, codec.encode_command("GET_INFO", 0) + codec.encode_command("START", 1))
    data = dev.read(0x81, 4096, timeout=200)          # array('B'): INFO, ACK, ROWs...
    print(dev.serial_number)                          # "carpet-01"
    backend.unplug()                                  # dev.read(...) now raises USBError(errno=19)
"""

from __future__ import annotations

import errno
import threading
import time
from types import SimpleNamespace
from typing import Callable

import usb.core
import usb.util
from usb.backend import IBackend

from firmware_protocol.virtual_board import VirtualBoard

DEFAULT_VID = 0x1209  # pid.codes, the open-source hardware VID
DEFAULT_PID = 0xCA7A  # our default; not registered: set vid/pid to what your board reports
EP_OUT = 0x01
EP_IN = 0x81
_POLL_S = 0.005  # longest a waiting read sleeps before looking again

# libusb error codes, as pyusb's libusb1 backend reports them
_LIBUSB = {
    "io": (-1, errno.EIO, "Input/output error"),
    "invalid": (-2, errno.EINVAL, "Invalid parameter"),
    "no_device": (-4, errno.ENODEV, "No such device (it may have been disconnected)"),
    "not_found": (-5, errno.ENOENT, "Entity not found"),
    "timeout": (-7, errno.ETIMEDOUT, "Operation timed out"),
    "overflow": (-8, errno.EOVERFLOW, "Overflow"),
    "pipe": (-9, errno.EPIPE, "Pipe error"),
}


def _error(kind: str) -> usb.core.USBError:
    code, err, text = _LIBUSB[kind]
    cls = usb.core.USBTimeoutError if kind == "timeout" else usb.core.USBError
    return cls(text, code, err)


def _string_descriptor(text: str) -> bytes:
    body = text.encode("utf-16-le")
    return bytes((2 + len(body), usb.util.DESC_TYPE_STRING)) + body


class _DeviceId:
    """What ``enumerate_devices`` yields: one enumeration of the board."""

    def __init__(self, generation: int, address: int) -> None:
        self.generation = generation
        self.address = address


class _Handle:
    """What ``open_device`` returns."""

    def __init__(self, dev: _DeviceId) -> None:
        self.dev = dev
        self.claimed: set[int] = set()
        self.closed = False


class VirtualUsbBackend(IBackend):
    """A pyusb backend with one fake vendor-class bulk device (see the module docstring)."""

    def __init__(
        self,
        board: VirtualBoard | None = None,
        *,
        vid: int = DEFAULT_VID,
        pid: int = DEFAULT_PID,
        manufacturer: str = "CAvatar",
        product: str = "CAvatar carpet readout (virtual)",
        max_packet_size: int = 64,  # 64: full speed; 512: high speed
        bus: int = 1,
        address: int = 7,
        clock: Callable[[], float] = time.monotonic,
        sleep: Callable[[float], None] = time.sleep,
        fifo_bytes: int = 1 << 20,
    ) -> None:
        self.board = board if board is not None else VirtualBoard()
        self.vid, self.pid = vid, pid
        self.manufacturer, self.product = manufacturer, product
        self.max_packet_size = max_packet_size
        self.bus = bus
        self._first_address = address
        self._clock, self._sleep = clock, sleep
        self.fifo_bytes = fifo_bytes
        self._fifo = bytearray()  # bytes the device has queued on its IN endpoint
        self._lock = threading.RLock()
        self.configuration = 1  # Linux configures a device as it enumerates
        self.halted: set[int] = set()
        self.counters = {"bytes_out": 0, "bytes_in": 0, "timeouts": 0, "overflow_bytes": 0, "fifo_dropped_bytes": 0}

    # ------------------------------------------------------------------ plug

    def unplug(self) -> None:
        """Pull the cable: transfers raise ENODEV, ``find`` sees nothing."""
        with self._lock:
            self.board.unplug(now_s=self._clock())
            self._fifo.clear()

    def replug(self) -> None:
        """Plug back in: the device enumerates again at a new address."""
        with self._lock:
            self.board.replug(now_s=self._clock())
            self.configuration = 1
            self.halted.clear()

    def _current(self) -> _DeviceId | None:
        if not self.board.plugged:
            return None
        gen = self.board.plug_generation
        return _DeviceId(gen, (self._first_address + gen - 1) % 127 + 1)

    def _check(self, handle_or_dev) -> None:
        dev = handle_or_dev.dev if isinstance(handle_or_dev, _Handle) else handle_or_dev
        if isinstance(handle_or_dev, _Handle) and handle_or_dev.closed:
            raise _error("invalid")
        if not self.board.plugged or dev.generation != self.board.plug_generation:
            raise _error("no_device")

    # ------------------------------------------------------------------ descriptors

    def enumerate_devices(self):
        dev = self._current()
        return [dev] if dev is not None else []

    def get_parent(self, dev):
        return None

    def get_device_descriptor(self, dev):
        major, minor, patch = self.board.fw_version
        return SimpleNamespace(
            bLength=18, bDescriptorType=usb.util.DESC_TYPE_DEVICE, bcdUSB=0x0200,
            bDeviceClass=0xFF, bDeviceSubClass=0, bDeviceProtocol=0, bMaxPacketSize0=64,
            idVendor=self.vid, idProduct=self.pid,
            bcdDevice=((major % 100) // 10 << 12) | (major % 10) << 8 | (minor % 10) << 4 | (patch % 10),
            iManufacturer=1, iProduct=2, iSerialNumber=3, bNumConfigurations=1,
            address=dev.address, bus=self.bus, port_number=1, port_numbers=(1,),
            speed=usb.util.SPEED_HIGH if self.max_packet_size == 512 else usb.util.SPEED_FULL,
        )

    def get_configuration_descriptor(self, dev, config):
        if config != 0:
            raise IndexError("configuration index out of range")
        return SimpleNamespace(
            bLength=9, bDescriptorType=usb.util.DESC_TYPE_CONFIG, wTotalLength=9 + 9 + 7 + 7,
            bNumInterfaces=1, bConfigurationValue=1, iConfiguration=0, bmAttributes=0x80,
            bMaxPower=250, extra_descriptors=[],
        )

    def get_interface_descriptor(self, dev, intf, alt, config):
        if config != 0 or intf != 0 or alt != 0:
            raise IndexError("interface index out of range")
        return SimpleNamespace(
            bLength=9, bDescriptorType=usb.util.DESC_TYPE_INTERFACE, bInterfaceNumber=0,
            bAlternateSetting=0, bNumEndpoints=2, bInterfaceClass=0xFF, bInterfaceSubClass=0,
            bInterfaceProtocol=0, iInterface=0, extra_descriptors=[],
        )

    def get_endpoint_descriptor(self, dev, ep, intf, alt, config):
        if config != 0 or intf != 0 or alt != 0 or ep not in (0, 1):
            raise IndexError("endpoint index out of range")
        return SimpleNamespace(
            bLength=7, bDescriptorType=usb.util.DESC_TYPE_ENDPOINT, bEndpointAddress=(EP_OUT, EP_IN)[ep],
            bmAttributes=usb.util.ENDPOINT_TYPE_BULK, wMaxPacketSize=self.max_packet_size, bInterval=0,
            bRefresh=0, bSynchAddress=0, extra_descriptors=[],
        )

    def _raw_descriptor(self, desc_type: int, index: int) -> bytes:
        if desc_type == usb.util.DESC_TYPE_STRING:
            if index == 0:
                return bytes((4, usb.util.DESC_TYPE_STRING, 0x09, 0x04))  # en-US
            strings = {1: self.manufacturer, 2: self.product, 3: self.board.device_id}
            if index not in strings:
                raise _error("pipe")
            return _string_descriptor(strings[index])
        if desc_type == usb.util.DESC_TYPE_DEVICE:
            d = self.get_device_descriptor(self._current())
            return bytes((18, 1, 0x00, 0x02, d.bDeviceClass, 0, 0, 64)) + d.idVendor.to_bytes(2, "little") + \
                d.idProduct.to_bytes(2, "little") + d.bcdDevice.to_bytes(2, "little") + bytes((1, 2, 3, 1))
        if desc_type == usb.util.DESC_TYPE_CONFIG:
            mps = self.max_packet_size.to_bytes(2, "little")
            return (bytes((9, 2, 32, 0, 1, 1, 0, 0x80, 250)) + bytes((9, 4, 0, 0, 2, 0xFF, 0, 0, 0))
                    + bytes((7, 5, EP_OUT, 2)) + mps + b"\x00" + bytes((7, 5, EP_IN, 2)) + mps + b"\x00")
        raise _error("pipe")

    # ------------------------------------------------------------------ handles and configuration

    def open_device(self, dev):
        self._check(dev)
        return _Handle(dev)

    def close_device(self, dev_handle):
        dev_handle.closed = True  # never fails, like libusb_close

    def set_configuration(self, dev_handle, config_value):
        self._check(dev_handle)
        if config_value not in (0, 1, -1):
            raise _error("not_found")
        self.configuration = max(config_value, 0)

    def get_configuration(self, dev_handle):
        self._check(dev_handle)
        return self.configuration

    def set_interface_altsetting(self, dev_handle, intf, altsetting):
        self._check(dev_handle)
        if intf != 0 or altsetting != 0:
            raise _error("not_found")

    def claim_interface(self, dev_handle, intf):
        self._check(dev_handle)
        if self.configuration != 1 or intf != 0:
            raise _error("not_found")
        dev_handle.claimed.add(intf)

    def release_interface(self, dev_handle, intf):
        self._check(dev_handle)
        dev_handle.claimed.discard(intf)

    def is_kernel_driver_active(self, dev_handle, intf):
        self._check(dev_handle)
        return False

    def detach_kernel_driver(self, dev_handle, intf):
        self._check(dev_handle)

    def attach_kernel_driver(self, dev_handle, intf):
        self._check(dev_handle)

    def clear_halt(self, dev_handle, ep):
        self._check(dev_handle)
        self.halted.discard(ep)

    def reset_device(self, dev_handle):
        """A USB reset: the device's queued IN data is lost; the board keeps running."""
        self._check(dev_handle)
        with self._lock:
            self._fifo.clear()
            self.halted.clear()

    # ------------------------------------------------------------------ transfers

    def bulk_write(self, dev_handle, ep, intf, data, timeout):
        self._check_transfer(dev_handle, ep, intf, EP_OUT)
        payload = bytes(data)
        with self._lock:
            self.board.receive(payload, now_s=self._clock())
        self.counters["bytes_out"] += len(payload)
        return len(payload)

    def bulk_read(self, dev_handle, ep, intf, buff, timeout):
        self._check_transfer(dev_handle, ep, intf, EP_IN)
        size = len(buff) * buff.itemsize
        deadline = None if not timeout else self._clock() + timeout / 1000.0
        while True:
            with self._lock:
                self._check(dev_handle)
                self._pull()
                if self._fifo:
                    n = self._take(size)
                    data = self._fifo[:n]
                    del self._fifo[:n]
                    break
                due = self.board.next_due_s()
            now = self._clock()
            if deadline is not None and now >= deadline:
                self.counters["timeouts"] += 1
                raise _error("timeout")
            wait = _POLL_S if due is None else max(0.0, due - now)
            if deadline is not None:
                wait = min(wait, deadline - now)
            self._sleep(min(wait, _POLL_S))
        memoryview(buff).cast("B")[:n] = data
        self.counters["bytes_in"] += n
        return n

    def intr_write(self, dev_handle, ep, intf, data, timeout):
        raise _error("invalid")  # the device has no interrupt endpoints

    def intr_read(self, dev_handle, ep, intf, buff, timeout):
        raise _error("invalid")

    def ctrl_transfer(self, dev_handle, bmRequestType, bRequest, wValue, wIndex, data, timeout):
        self._check(dev_handle)
        direction_in = bmRequestType & 0x80
        kind = bmRequestType & 0x60
        if kind != usb.util.CTRL_TYPE_STANDARD:
            raise _error("pipe")  # no vendor or class requests: the device stalls them
        if direction_in and bRequest == 0x06:  # GET_DESCRIPTOR
            raw = self._raw_descriptor(wValue >> 8, wValue & 0xFF)
        elif direction_in and bRequest == 0x00:  # GET_STATUS
            raw = b"\x00\x00"
        elif direction_in and bRequest == 0x08:  # GET_CONFIGURATION
            raw = bytes((self.configuration,))
        elif not direction_in and bRequest in (0x01, 0x03):  # CLEAR_FEATURE, SET_FEATURE
            return len(data)
        elif not direction_in and bRequest == 0x09:  # SET_CONFIGURATION
            self.set_configuration(dev_handle, wValue)
            return len(data)
        else:
            raise _error("pipe")
        n = min(len(raw), len(data) * data.itemsize)
        memoryview(data).cast("B")[:n] = raw[:n]
        return n

    # ------------------------------------------------------------------ internals

    def _check_transfer(self, dev_handle, ep, intf, expected_ep) -> None:
        self._check(dev_handle)
        if ep != expected_ep or intf != 0:
            raise _error("invalid")
        if intf not in dev_handle.claimed:
            raise _error("not_found")  # pyusb claims the interface before every transfer
        if ep in self.halted:
            raise _error("pipe")

    def _pull(self) -> None:
        data = self.board.read(self._clock())
        if data:
            room = self.fifo_bytes - len(self._fifo)
            if len(data) > room:
                self.counters["fifo_dropped_bytes"] += len(data) - max(room, 0)
                data = data[: max(room, 0)]
            self._fifo += data

    def _take(self, size: int) -> int:
        """Bytes one bulk IN transfer of ``size`` takes from the FIFO; EOVERFLOW as the host controller reports it."""
        mps = self.max_packet_size
        avail = len(self._fifo)
        full = size - size % mps
        if avail <= full or size % mps == 0:
            return min(avail, size)
        tail = min(mps, avail - full)  # the next USB packet after the full ones
        if tail > size % mps:
            lost = full + tail
            self.counters["overflow_bytes"] += lost
            del self._fifo[:lost]
            raise _error("overflow")
        return full + tail
