"""Without --config, `cavatar doctor`, `status` and `run` use the installed configuration (issue 17, finding 6):
--config, else $CAVATAR_CONFIG, else /etc/cavatar/cavatar.toml when it exists, else the built-in defaults — and
each says which. On an installed board `doctor` used to check the virtual carpet and say "ready"."""

import json

import pytest
from deploy_helpers import run_cli

from edge.runtime import config_choice
from edge.runtime.config_choice import choose_config


@pytest.fixture
def installed(monkeypatch, config, tmp_path):
    """An 'installed' board: /etc/cavatar/cavatar.toml stands in a tmp folder, naming a serial board not plugged in."""
    path = config(source={"url": "serial:///dev/ttyCAVATAR-NOT-HERE?baud=2000000"})
    monkeypatch.setattr(config_choice, "SYSTEM_CONFIG", str(path))
    monkeypatch.delenv("CAVATAR_CONFIG", raising=False)
    return path


def test_the_order_is_flag_environment_installed_defaults(tmp_path, monkeypatch):
    system = tmp_path / "etc.toml"
    monkeypatch.setattr(config_choice, "SYSTEM_CONFIG", str(system))
    assert choose_config(None, env={}).path is None
    system.write_text("")
    assert choose_config(None, env={}).path == str(system)
    assert choose_config(None, env={"CAVATAR_CONFIG": "/x.toml"}).path == "/x.toml"
    assert choose_config(None, env={"CAVATAR_CONFIG": "  "}).path == str(system)
    assert choose_config("/flag.toml", env={"CAVATAR_CONFIG": "/x.toml"}).path == "/flag.toml"
    assert "CAVATAR_CONFIG" in choose_config(None, env={"CAVATAR_CONFIG": "/x.toml"}).describe


def test_doctor_without_config_checks_the_installed_board_not_the_virtual_carpet(installed, capsys):
    code, out = run_cli(["doctor", "--no-open"], capsys)
    assert code == 1, out
    assert f"{installed} (the installed one; --config FILE for another) is valid" in out
    assert "/dev/ttyCAVATAR-NOT-HERE" in out and "NOT ready" in out
    code, out = run_cli(["doctor", "--no-open", "--json"], capsys)
    assert json.loads(out)["config"] == str(installed)


def test_status_without_config_reads_the_installed_status_file(installed, tmp_path, capsys):
    code, out = run_cli(["status"], capsys)
    assert code == 2 and f"no status file {tmp_path / 'out' / 'status.json'}" in out
    assert f"configuration {installed} (the installed one" in out
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "status.json").write_text(json.dumps({"schema": "cavatar.status/1", "device": "carpet-9",
                                                              "state": "running", "updated": 0}))
    code, out = run_cli(["status"], capsys)
    assert code == 0 and out.startswith(f"status file {tmp_path / 'out' / 'status.json'} (configuration {installed}")
    assert "device carpet-9: running" in out


def test_the_environment_variable_wins_and_a_missing_file_says_where_it_came_from(installed, monkeypatch, tmp_path,
                                                                                   capsys):
    monkeypatch.setenv("CAVATAR_CONFIG", str(tmp_path / "gone.toml"))
    code, out = run_cli(["run", "--seconds", "1"], capsys)
    assert code == 2 and f"{tmp_path / 'gone.toml'} (from $CAVATAR_CONFIG)" in out and "no such file" in out
    assert "Traceback" not in out


def test_run_without_config_names_the_installed_configuration(installed, capsys):
    code, out = run_cli(["run", "--seconds", "1"], capsys)
    assert code == 2 and "/dev/ttyCAVATAR-NOT-HERE" in out  # the installed board, not the virtual carpet


def test_run_says_which_configuration_it_uses(config, monkeypatch, capsys):
    path = config()
    monkeypatch.setenv("CAVATAR_CONFIG", str(path))
    code, out = run_cli(["run", "--seconds", "0.5", "--quiet"], capsys)
    assert code == 0, out
    assert f"(configuration {path} (from $CAVATAR_CONFIG))" in out
