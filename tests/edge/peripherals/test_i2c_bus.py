"""Opening real buses (error messages), the fake bus's SMBus semantics, the chip registry."""

import errno
import os
import sys

import pytest

import edge.peripherals as peripherals
from edge.cli import main
from edge.peripherals.fakebus import FakeBus, FakeMCP4018, FakeTMP102
from edge.peripherals.i2c import I2CBusError, bus_path, list_buses, open_bus


@pytest.fixture
def dev_dir(tmp_path):
    for name in ("i2c-10", "i2c-2", "i2c-1", "ttyS0"):
        (tmp_path / name).write_bytes(b"")
    return tmp_path


def test_missing_bus_names_it_and_lists_existing_buses(dev_dir):
    with pytest.raises(I2CBusError) as info:
        open_bus(3, dev_dir=str(dev_dir))
    message = str(info.value)
    assert info.value.errno == errno.ENOENT
    assert f"{dev_dir}/i2c-3 does not exist" in message
    assert message.endswith(f"{dev_dir}/i2c-1, {dev_dir}/i2c-2, {dev_dir}/i2c-10")


def test_missing_bus_path_with_no_buses_says_none(tmp_path):
    with pytest.raises(I2CBusError, match=r"/nonexistent/i2c-9 does not exist.*none"):
        open_bus("/nonexistent/i2c-9", dev_dir=str(tmp_path))


def test_a_file_that_is_not_an_adapter_is_refused(dev_dir):
    with pytest.raises(I2CBusError, match="is not a usable I²C bus"):
        open_bus(str(dev_dir / "ttyS0"), dev_dir=str(dev_dir))


def test_missing_smbus2_is_reported(monkeypatch):
    monkeypatch.setitem(sys.modules, "smbus2", None)
    with pytest.raises(I2CBusError, match="smbus2 is not installed"):
        open_bus(1)


def test_bus_names():
    assert bus_path(1) == "/dev/i2c-1" and bus_path("7") == "/dev/i2c-7"
    assert bus_path("/dev/i2c-4") == "/dev/i2c-4"
    for bad in (-1, 1.5, True, None):
        with pytest.raises(ValueError):
            bus_path(bad)
    assert list_buses("/no/such/dir") == []


@pytest.mark.parametrize("call", [
    lambda bus: bus.read_byte(0x50), lambda bus: bus.write_byte(0x50, 1),
    lambda bus: bus.read_byte_data(0x50, 0), lambda bus: bus.write_byte_data(0x50, 0, 1),
    lambda bus: bus.read_word_data(0x50, 0), lambda bus: bus.write_word_data(0x50, 0, 1),
    lambda bus: bus.read_i2c_block_data(0x50, 0, 2), lambda bus: bus.write_quick(0x50),
    lambda bus: bus.write_i2c_block_data(0x50, 0, [1, 2]),
])
def test_absent_address_is_remote_io_error_like_linux(call):
    bus = FakeBus({0x48: FakeTMP102()})
    with pytest.raises(OSError) as info:
        call(bus)
    assert info.value.errno == errno.EREMOTEIO == 121
    assert info.value.strerror == os.strerror(121)


def test_write_word_data_sends_the_low_byte_first():
    chip = FakeTMP102()
    bus = FakeBus({0x48: chip})
    bus.write_word_data(0x48, 0x03, 0x5000)       # meant 80 °C, lands as 0x0050
    assert chip.limits[0x03] == 0x0050
    bus.write_i2c_block_data(0x48, 0x03, [0x50, 0x00])
    assert chip.limits[0x03] == 0x5000
    assert bus.read_i2c_block_data(0x48, 0x03, 2) == [0x50, 0x00]


def test_fake_bus_refuses_bad_values_addresses_and_use_after_close():
    bus = FakeBus({0x2F: FakeMCP4018()})
    with pytest.raises(ValueError):
        bus.write_byte(0x2F, 256)
    with pytest.raises(ValueError):
        bus.read_i2c_block_data(0x2F, 0, 33)
    with pytest.raises(OSError) as info:
        bus.read_byte(0x80)
    assert info.value.errno == errno.EINVAL
    bus.close()
    with pytest.raises(OSError) as info:
        bus.read_byte(0x2F)
    assert info.value.errno == errno.EBADF


def test_i2c_rdwr_with_smbus2_messages():
    smbus2 = pytest.importorskip("smbus2")
    bus = FakeBus({0x48: FakeTMP102(-25.0)})
    write, read = smbus2.i2c_msg.write(0x48, [0x00]), smbus2.i2c_msg.read(0x48, 2)
    bus.i2c_rdwr(write, read)
    assert list(read) == [0xE7, 0x00]


def test_registry_names_and_unknown_chip():
    assert set(peripherals.available_chips()) == {"tmp102", "mcp4018"}
    assert all(why is None for why in peripherals.available_chips().values())
    with pytest.raises(ValueError, match="accepted: mcp4018, tmp102"):
        peripherals.open_chip("lm75", FakeBus())


def test_a_chip_that_fails_to_import_is_reported_not_fatal(monkeypatch):
    chips = dict(peripherals.CHIPS, broken=(peripherals.TemperatureSensor, "edge.no_such_module:X"))
    monkeypatch.setattr(peripherals, "CHIPS", chips)
    status = peripherals.available_chips()
    assert "edge.no_such_module" in status["broken"]
    assert status["tmp102"] is None and status["mcp4018"] is None


def test_cli_reads_the_emulated_bus(capsys):
    assert main(["peripherals", "--fake", "--set-step", "100"]) == 0
    out = capsys.readouterr().out
    assert "temperature_c: 24.5000" in out and "gain_step: 100 of 0..127" in out


def test_cli_reports_an_absent_chip_and_a_missing_bus(capsys):
    assert main(["peripherals", "--fake", "--sensor-address", "0x49"]) == 1
    assert "Remote I/O error" in capsys.readouterr().out
    assert main(["peripherals", "--bus", "/nonexistent/i2c-9"]) == 2
    assert "/nonexistent/i2c-9 does not exist" in capsys.readouterr().err
