"""`cavatar peripherals`: read the board's I²C temperature sensor and gain potentiometer."""

from __future__ import annotations

import argparse
import errno

from edge.cli import CliError, command_name
from edge.peripherals import CHIPS, GainControl, TemperatureSensor, chip_kind, open_chip


def _address(text: str) -> int:
    try:
        value = int(text, 0)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not an I²C address: {text!r} (e.g. 0x48)") from None
    if not 0 <= value <= 0x7F:
        raise argparse.ArgumentTypeError(f"I²C address must be in 0x00..0x7f, got {text}")
    return value


def _chip(kind: type):
    names = [name for name in CHIPS if chip_kind(name) is kind]

    def parse(text: str) -> str:
        if text not in names:
            raise argparse.ArgumentTypeError(f"unknown chip {text!r}; accepted: {', '.join(names)}")
        return text
    return parse


def register(subparsers) -> None:
    p = subparsers.add_parser(
        command_name(__name__), help="read the board's I²C temperature sensor and gain setting",
        description="Read the host board's I²C temperature sensor and front-end gain "
                    "potentiometer; optionally set the gain. --fake uses an emulated bus.")
    p.add_argument("--bus", default="1", help="I²C bus number or path (default: 1, /dev/i2c-1)")
    p.add_argument("--fake", action="store_true", help="use an emulated bus (TMP102 + MCP4018)")
    p.add_argument("--sensor", default="tmp102", type=_chip(TemperatureSensor),
                   help="temperature sensor chip (default: tmp102)")
    p.add_argument("--sensor-address", type=_address, help="its address (default: the chip's)")
    p.add_argument("--gain", default="mcp4018", type=_chip(GainControl),
                   help="gain potentiometer chip (default: mcp4018)")
    p.add_argument("--gain-address", type=_address, help="its address (default: the chip's)")
    setting = p.add_mutually_exclusive_group()
    setting.add_argument("--set-step", type=int, metavar="STEP", help="set the gain step first")
    setting.add_argument("--set-gain", type=float, metavar="FRACTION",
                         help="set the gain to FRACTION (0..1) of full scale first")
    p.set_defaults(func=run)


def _why(exc: OSError) -> str:
    if exc.errno == errno.EREMOTEIO:
        return f"{exc} (no device answers at that address)"
    return str(exc)


def run(args: argparse.Namespace) -> int:
    if args.fake:
        from edge.peripherals.fakebus import demo_bus
        bus, where = demo_bus(), "emulated bus"
    else:
        from edge.peripherals.i2c import open_bus
        try:
            bus = open_bus(args.bus)
        except (OSError, ValueError) as exc:
            raise CliError(str(exc)) from None
        where = str(args.bus)
    failures = 0
    print(f"bus: {where}")
    try:
        try:
            sensor = open_chip(args.sensor, bus, args.sensor_address)
            print(f"temperature_c: {sensor.read_temperature_c():.4f}  "
                  f"({args.sensor} at {sensor.address:#04x})")
        except ValueError as exc:
            raise CliError(str(exc)) from None
        except OSError as exc:  # includes TimeoutError
            failures += 1
            print(f"temperature_c: unavailable: {args.sensor}: {_why(exc)}")
        try:
            gain = open_chip(args.gain, bus, args.gain_address)
            if args.set_step is not None:
                gain.set_step(args.set_step)
            elif args.set_gain is not None:
                gain.set_gain_fraction(args.set_gain)
            step = gain.step()
            print(f"gain_step: {step} of 0..{gain.step_count - 1}, gain fraction "
                  f"{step / (gain.step_count - 1):.3f}  ({args.gain} at {gain.address:#04x})")
        except ValueError as exc:
            raise CliError(str(exc)) from None
        except OSError as exc:
            failures += 1
            print(f"gain_step: unavailable: {args.gain}: {_why(exc)}")
    finally:
        bus.close()
    return 1 if failures else 0
