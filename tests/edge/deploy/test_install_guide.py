"""docs/install-pi.md: every `cavatar ...` command it shows exists, and so does every flag given to it."""

import re

import pytest
from deploy_helpers import GUIDE, run_cli

# `cavatar` as a command (also /opt/cavatar/venv/bin/cavatar), followed by its subcommand word
COMMAND = re.compile(r"(?:^|(?<=[\s/`(]))cavatar[ \t]+([a-z][a-z-]*)(?:[ \t]+([a-z][a-z-]*))?([^|;&>`]*)")
ACTIONS = {"config", "sim"}  # subcommands whose next word is an action (config validate, sim show)


def code_lines() -> list[str]:
    """Fenced code lines (backslash continuations joined) and inline `code` spans of the guide."""
    text = GUIDE.read_text()
    out = []
    for block in re.findall(r"```[a-z]*\n(.*?)```", text, re.S):
        out += block.replace("\\\n", " ").splitlines()
    prose = re.sub(r"```[a-z]*\n.*?```", "", text, flags=re.S)
    out += re.findall(r"`([^`\n]+)`", prose)
    return out


def commands() -> dict[tuple[str, ...], set[str]]:
    """(subcommand[, action]) → the flags the guide gives it."""
    found: dict[tuple[str, ...], set[str]] = {}
    for line in code_lines():
        for sub, action, rest in COMMAND.findall(line):
            key = (sub, action) if sub in ACTIONS and action else (sub,)
            tail = rest if sub in ACTIONS or not action else f"{action}{rest}"
            found.setdefault(key, set()).update(re.findall(r"(?<![\w-])(--[a-z][a-z-]*)", tail))
    return found


def test_the_guide_shows_the_commands_of_an_installation():
    found = commands()
    for key in [("devices",), ("calibrate",), ("config", "validate"), ("doctor",), ("status",), ("stream",)]:
        assert key in found, key
    assert found[("calibrate",)] >= {"--source", "--mass", "--out"}
    assert found[("doctor",)] >= {"--config"}


@pytest.mark.parametrize("key", sorted(commands()), ids=lambda k: " ".join(k))
def test_every_command_and_flag_of_the_guide_exists(key, capsys):
    code, help_text = run_cli([*key, "--help"], capsys)
    assert code == 0, f"`cavatar {' '.join(key)} --help` failed:\n{help_text}"
    for flag in sorted(commands()[key]):
        assert re.search(rf"(?<![\w-]){re.escape(flag)}(?![\w-])", help_text), \
            f"`cavatar {' '.join(key)}` has no {flag}:\n{help_text}"


def test_the_guide_names_the_deploy_files_and_paths():
    text = GUIDE.read_text()
    for needle in ("deploy/install.sh", "deploy/cavatar.service", "deploy/99-cavatar.rules", "/etc/cavatar/cavatar.toml",
                   "/etc/cavatar/cavatar.env", "CAVATAR_MQTT_PASSWORD", "journalctl -u cavatar -f", "mosquitto_sub",
                   "/dev/cavatar-carpet", "systemctl enable --now cavatar"):
        assert needle in text, needle
    assert "Pi 5" in text and "Pi 4" in text and "dot-product" in text
