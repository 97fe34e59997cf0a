"""The runtime's TOML configuration: typed, every key described, unknown keys and secrets refused."""

import re
import tomllib
from pathlib import Path

import pytest

from edge.cli import main
from edge.runtime.config import ConfigError, RuntimeConfig, default_bundle_path, load_config
from edge.runtime.config_docs import describe, to_toml

REPO = Path(__file__).resolve().parents[3]
EXAMPLE = REPO / "deploy" / "cavatar.example.toml"


def write(tmp_path, text: str) -> Path:
    p = tmp_path / "cavatar.toml"
    p.write_text(text)
    return p


def test_defaults_give_the_shipped_bundle_the_virtual_carpet_and_a_jsonl_file():
    cfg = RuntimeConfig()
    assert cfg.bundle_path() == default_bundle_path()
    assert (default_bundle_path() / "manifest.json").is_file() and (default_bundle_path() / "encoder.onnx").is_file()
    assert cfg.source.url.startswith("sim://")
    assert cfg.sinks.urls == ["jsonl://out/cavatar/bodies.jsonl"]
    assert cfg.runtime.seconds == 0.0 and cfg.runtime.heartbeat_s == 1.0


def test_unknown_keys_are_refused_with_the_known_ones(tmp_path):
    p = write(tmp_path, '[source]\nurl = "sim://?people=1"\nqueue = 3\n[sinkz]\nurls = []\n')
    with pytest.raises(ConfigError) as exc:
        load_config(p)
    problems = exc.value.problems
    assert any(pr.startswith("source.queue: unknown key") and "queue_frames" in pr and "url" in pr for pr in problems)
    assert any(pr.startswith("sinkz: unknown key") and "sinks" in pr and "runtime" in pr for pr in problems)


def test_every_wrong_type_is_named_with_its_key_path_all_at_once(tmp_path):
    p = write(tmp_path, """
[source]
queue_frames = "four"
[model]
threads = 1.5
[runtime]
seconds = "ten"
heartbeat_s = -1
[scene]
birth_frames = "3"
coast_s = -2.0
[calibration.baseline]
tau_s = "slow"
""")
    with pytest.raises(ConfigError) as exc:
        load_config(p)
    text = str(exc.value)
    for path in ("source.queue_frames", "model.threads", "runtime.seconds", "runtime.heartbeat_s", "scene.birth_frames",
                 "scene.coast_s", "calibration.baseline.tau_s"):
        assert re.search(rf"^\s+- {re.escape(path)}: ", text, re.M), (path, text)
    assert "must be an integer, got a string 'four'" in text
    assert len(exc.value.problems) == 7


def test_bad_urls_are_problems_that_quote_the_accepted_form():
    with pytest.raises(ConfigError) as exc:
        RuntimeConfig.from_dict({"source": {"url": "tcp://board"}, "sinks": {"urls": ["jsonl:///x.jsonl?rotate=1", "kafka://x"]}})
    text = str(exc.value)
    assert "source.url: unknown source 'tcp://board'" in text and "sim://?people=2&seed=7" in text
    assert "jsonl:// sink has no option 'rotate'" in text and "unknown sink 'kafka://x'" in text


def test_secrets_are_refused_in_the_file_and_taken_from_the_environment(tmp_path):
    p = write(tmp_path, '[sinks]\nurls = ["mqtt://cavatar@broker/cavatar"]\npassword = "hunter2"\n')
    with pytest.raises(ConfigError) as exc:
        load_config(p)
    (problem,) = exc.value.problems
    assert problem.startswith("sinks.password: secrets never go in the configuration file")
    assert "CAVATAR_MQTT_PASSWORD" in problem and "hunter2" not in str(exc.value)
    with pytest.raises(ConfigError) as exc:
        RuntimeConfig.from_dict({"sinks": {"urls": ["mqtt://cavatar:hunter2@broker/cavatar"]}})
    assert "CAVATAR_MQTT_PASSWORD" in str(exc.value) and "hunter2" not in str(exc.value)


def test_overrides_replace_file_values_and_are_checked(tmp_path):
    cfg = load_config(write(tmp_path, '[source]\nurl = "sim://?people=1"\n[runtime]\nseconds = 5\n'))
    assert cfg.runtime.seconds == 5.0 and isinstance(cfg.runtime.seconds, float)
    o = cfg.with_overrides(source="sim://?people=0", sinks=["jsonl:-", "jsonl://a.jsonl"], seconds=2, device="hall-2",
                           bundle="/opt/b", calibration="c.npz")
    assert (o.source.url, o.sinks.urls, o.runtime.seconds, o.device.id) == (
        "sim://?people=0", ["jsonl:-", "jsonl://a.jsonl"], 2.0, "hall-2")
    assert o.bundle_path() == Path("/opt/b") and o.calibration.file == "c.npz"
    assert cfg.source.url == "sim://?people=1"  # the original is unchanged
    with pytest.raises(ConfigError) as exc:
        cfg.with_overrides(device="bad/id", seconds=-1)
    assert {p.split(":")[0] for p in exc.value.problems} == {"device.id", "runtime.seconds"}


def test_describe_covers_every_key_and_the_toml_round_trips():
    rows = describe()
    keys = [r.key for r in rows]
    assert len(keys) == len(set(keys))
    assert {"device.id", "source.url", "source.queue_frames", "calibration.file", "calibration.max_age_days",
            "calibration.baseline.tau_s", "model.bundle", "model.threads", "scene.coast_s", "sinks.urls",
            "runtime.status_file", "runtime.seconds", "runtime.summary_s", "runtime.heartbeat_s"} <= set(keys)
    assert all(r.doc and r.type and r.default for r in rows)
    text = to_toml()
    assert RuntimeConfig.from_dict(tomllib.loads(text)) == RuntimeConfig()


def test_the_example_file_is_valid_and_mentions_every_key(tmp_path):
    cfg = load_config(EXAMPLE)
    assert cfg.sinks.urls[0].startswith("mqtt://cavatar@") and cfg.calibration.file
    text = EXAMPLE.read_text()
    for row in describe():
        leaf = row.key.rsplit(".", 1)[1]
        assert re.search(rf"^#? ?{leaf} = ", text, re.M), f"{row.key} is not in {EXAMPLE.name}"
    # uncommenting every example value still gives a valid configuration
    uncommented = re.sub(r"^# ([a-z_0-9]+ = .+)$", r"\1", text, flags=re.M)
    assert uncommented.count("\n# ") < text.count("\n# ")
    assert load_config(write(tmp_path, uncommented)).scene.noise_kpa == 0.05


def test_cli_validate_and_show(tmp_path, capsys):
    assert main(["config", "validate", str(EXAMPLE)]) == 0
    out = capsys.readouterr().out
    assert "valid" in out and "carpet-living-room" in out
    bad = write(tmp_path, '[source]\nqueue_frames = 0\nurl = 3\n[nope]\n')
    assert main(["config", "validate", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "3 problem(s)" in err and "source.queue_frames: must be ≥ 1" in err and "source.url: must be a string" in err
    assert "nope: unknown key" in err
    assert main(["config", "validate", str(tmp_path / "missing.toml")]) == 2
    assert "no such file" in capsys.readouterr().err
    assert main(["config", "validate", str(write(tmp_path, "[source\n"))]) == 2
    assert "not valid TOML" in capsys.readouterr().err
    assert main(["config", "show"]) == 0
    out = capsys.readouterr().out
    for row in describe():
        assert row.key in out
    assert main(["config", "show", "--toml"]) == 0
    assert RuntimeConfig.from_dict(tomllib.loads(capsys.readouterr().out)) == RuntimeConfig()
