"""MCP4018 driver against the emulated chip: wiper range, round trip, wire format."""

import errno
import math

import pytest

from edge.peripherals import GainControl, open_chip
from edge.peripherals.fakebus import FakeBus, FakeMCP4018, FakeTMP102
from edge.peripherals.mcp4018 import MCP4018

ADDRESS = 0x2F


def make():
    chip = FakeMCP4018()
    bus = FakeBus({ADDRESS: chip})
    return bus, chip, MCP4018(bus)


def test_power_on_wiper_is_mid_scale():
    _, _, pot = make()
    assert pot.wiper() == 0x3F


def test_every_step_round_trips():
    _, chip, pot = make()
    for step in range(128):
        pot.set_wiper(step)
        assert chip.wiper_step == step
        assert pot.wiper() == step


def test_write_is_one_data_byte_without_register_address():
    bus, _, pot = make()
    pot.set_wiper(100)
    assert list(bus.log) == [("w", ADDRESS, bytes([100]))]


@pytest.mark.parametrize("step", [-1, 128, 255, 1.5, True, "3"])
def test_out_of_range_step_is_refused_before_the_bus(step):
    bus, chip, pot = make()
    with pytest.raises(ValueError, match=r"0\.\.127"):
        pot.set_wiper(step)
    assert chip.wiper_step == 0x3F and not bus.log


def test_emulated_chip_ignores_msb_and_keeps_the_last_data_byte():
    bus, chip, _ = make()
    bus.write_byte(ADDRESS, 0x80 | 5)
    assert chip.wiper_step == 5 and bus.read_byte(ADDRESS) == 5
    bus.write_byte_data(ADDRESS, 0x10, 0x20)          # two data bytes: the second wins
    assert chip.wiper_step == 0x20


@pytest.mark.parametrize("fraction, step", [(0.0, 0), (1.0, 127), (0.5, 64), (0.25, 32), (1, 127)])
def test_gain_fraction_maps_to_the_nearest_step(fraction, step):
    _, chip, pot = make()
    assert pot.set_gain_fraction(fraction) == step
    assert chip.wiper_step == step
    assert pot.gain_fraction() == pytest.approx(step / 127)


@pytest.mark.parametrize("fraction", [-0.01, 1.01, math.nan, math.inf, None, True])
def test_gain_fraction_out_of_range_says_the_range(fraction):
    _, chip, pot = make()
    with pytest.raises(ValueError, match=r"\[0, 1\]"):
        pot.set_gain_fraction(fraction)
    assert chip.wiper_step == 0x3F


def test_absent_potentiometer_is_remote_io_error():
    pot = MCP4018(FakeBus())
    for call in (pot.wiper, lambda: pot.set_wiper(1)):
        with pytest.raises(OSError) as info:
            call()
        assert info.value.errno == errno.EREMOTEIO


def test_a_byte_with_msb_set_is_not_taken_for_a_wiper():
    # a TMP102 answering at 0x2F at -25 °C returns 0xE7 first: bit 7 set
    pot = MCP4018(FakeBus({ADDRESS: FakeTMP102(-25.0)}))
    with pytest.raises(OSError, match="bit 7"):
        pot.wiper()


def test_registry_opens_it_as_a_gain_control():
    bus = FakeBus({ADDRESS: FakeMCP4018(10)})
    gain = open_chip("mcp4018", bus)
    assert isinstance(gain, GainControl) and gain.step_count == 128
    assert gain.step() == 10
    gain.set_step(127)
    assert gain.gain_fraction() == 1.0
