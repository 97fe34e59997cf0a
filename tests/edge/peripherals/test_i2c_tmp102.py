"""TMP102 driver against the emulated chip: datasheet byte vectors, both modes, one-shot."""

import errno

import pytest

from edge.peripherals import TemperatureSensor, open_chip
from edge.peripherals.fakebus import FakeBus, FakeTMP102
from edge.peripherals.tmp102 import TMP102, decode_temperature_c

ADDRESS = 0x48

# (°C, byte 1, byte 2) from the datasheet's data-format tables (12-bit, D0 = 0)
NORMAL = [
    (25.0625, 0x19, 0x10), (-25.0, 0xE7, 0x00), (0.0, 0x00, 0x00),
    (127.9375, 0x7F, 0xF0), (-128.0, 0x80, 0x00), (100.0, 0x64, 0x00),
    (-55.0, 0xC9, 0x00), (-0.25, 0xFF, 0xC0), (0.0625, 0x00, 0x10),
]
# 13-bit, D0 = 1
EXTENDED = [
    (150.0, 0x4B, 0x01), (25.0625, 0x0C, 0x89), (-25.0, 0xF3, 0x81), (0.0, 0x00, 0x01),
    (255.9375, 0x7F, 0xF9), (-256.0, 0x80, 0x01), (-55.0, 0xE4, 0x81), (128.0, 0x40, 0x01),
]


def make(temperature_c, **options):
    chip = FakeTMP102(temperature_c)
    bus = FakeBus({ADDRESS: chip})
    return bus, chip, TMP102(bus, ADDRESS, **options)


@pytest.mark.parametrize("temperature_c, msb, lsb", NORMAL)
def test_normal_mode_bytes_and_round_trip(temperature_c, msb, lsb):
    bus, _, sensor = make(temperature_c)
    assert bus.read_i2c_block_data(ADDRESS, 0x00, 2) == [msb, lsb]
    assert sensor.read_temperature_c() == temperature_c
    assert decode_temperature_c(msb, lsb) == temperature_c


@pytest.mark.parametrize("temperature_c, msb, lsb", EXTENDED)
def test_extended_mode_bytes_and_round_trip(temperature_c, msb, lsb):
    bus, _, sensor = make(temperature_c, extended=True)
    assert bus.read_i2c_block_data(ADDRESS, 0x00, 2) == [msb, lsb]
    assert sensor.read_temperature_c() == temperature_c
    assert sensor.extended


def test_read_word_data_is_little_endian_so_the_driver_avoids_it():
    bus, _, sensor = make(25.0625)
    assert bus.read_word_data(ADDRESS, 0x00) == 0x1019          # bytes swapped
    assert sensor.read_temperature_c() == 25.0625
    assert ("w", ADDRESS, b"\x00") in bus.log and ("r", ADDRESS, b"\x19\x10") in bus.log


def test_mode_is_taken_from_bit_d0_of_the_data():
    assert decode_temperature_c(0x4B, 0x00) == 75.0     # 12-bit 0x4B0
    assert decode_temperature_c(0x4B, 0x01) == 150.0    # 13-bit 0x0960


def test_normal_mode_saturates_and_extended_mode_reaches_150_c():
    bus, chip, sensor = make(150.0)
    assert sensor.read_temperature_c() == 127.9375
    chip.temperature_c = -300.0
    assert sensor.read_temperature_c() == -128.0
    TMP102(bus, ADDRESS, extended=True)
    chip.temperature_c = 150.0
    assert sensor.read_temperature_c() == 150.0


def test_configuration_writes_are_msb_first_and_keep_other_bits():
    bus, _, sensor = make(20.0)
    assert sensor.read_config() == 0x60A0                       # power-up value
    TMP102(bus, ADDRESS, extended=True)
    assert ("w", ADDRESS, bytes([0x01, 0x60, 0xB0])) in bus.log
    assert sensor.read_config() == 0x60B0
    TMP102(bus, ADDRESS, extended=False, shutdown=True)
    assert sensor.read_config() == 0x61A0 and sensor.shutdown and not sensor.extended


def test_shutdown_holds_the_last_result_and_one_shot_refreshes_it():
    bus, chip, sensor = make(21.0, shutdown=True)
    chip.temperature_c = 30.5
    assert bus.read_i2c_block_data(ADDRESS, 0x00, 2) == [0x15, 0x00]   # still 21 °C
    assert sensor.read_temperature_c() == 30.5
    assert sensor.read_config() & 0x8000                                 # OS: ready


class ManualClock:
    def __init__(self):
        self.now_s, self.sleeps = 0.0, 0

    def __call__(self):
        return self.now_s

    def sleep(self, duration_s):
        self.sleeps += 1
        self.now_s += duration_s


def test_one_shot_waits_for_the_conversion():
    clock = ManualClock()
    chip = FakeTMP102(-10.0, conversion_time_s=0.026, clock=clock)
    bus = FakeBus({ADDRESS: chip})
    sensor = TMP102(bus, ADDRESS, shutdown=True, sleep=clock.sleep, clock=clock)
    chip.temperature_c = -12.5
    assert sensor.read_temperature_c() == -12.5
    assert clock.sleeps >= 5 and clock.now_s >= 0.026


def test_one_shot_that_never_finishes_times_out():
    clock = ManualClock()
    chip = FakeTMP102(0.0, conversion_time_s=10.0, clock=clock)
    sensor = TMP102(FakeBus({ADDRESS: chip}), ADDRESS, shutdown=True, sleep=clock.sleep, clock=clock)
    with pytest.raises(TimeoutError, match="0x48"):
        sensor.read_temperature_c()


def test_absent_sensor_is_remote_io_error():
    with pytest.raises(OSError) as info:
        TMP102(FakeBus(), ADDRESS)
    assert info.value.errno == errno.EREMOTEIO


def test_bad_address_lists_the_valid_ones():
    with pytest.raises(ValueError, match="0x48, 0x49, 0x4a, 0x4b"):
        TMP102(FakeBus(), 0x40)


def test_registry_opens_it_as_a_temperature_sensor():
    bus = FakeBus({0x49: FakeTMP102(-3.0)})
    sensor = open_chip("tmp102", bus, 0x49)
    assert isinstance(sensor, TemperatureSensor)
    assert sensor.read_temperature_c() == -3.0
