"""`cavatar render` on stream records, and the renderer itself."""

import json

import numpy as np
import pytest

pytest.importorskip("matplotlib")

from edge.body.poses import POSES, pose_aa  # noqa: E402
from edge.cli import main  # noqa: E402


def _record(seq=1, people=1):
    return {
        "schema": "cavatar.bodies/1", "device": "carpet-01", "seq": seq, "time": 1732240000.0, "model": "m@0",
        "people": [
            {"track_id": k, "transl_m": [0.9 + 0.7 * k, 0.9, 0.95], "pose_aa": list(pose_aa("t_pose")), "betas": [0.0] * 10,
             "confidence": 0.9, "activity": "stand"}
            for k in range(people)
        ],
    }


def _png_ok(path):
    data = path.read_bytes()
    return data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 5000


def test_render_json_record(tmp_path):
    """A .json record with two people → a PNG, exit 0."""
    rec = tmp_path / "rec.json"
    rec.write_text(json.dumps(_record(people=2)))
    out = tmp_path / "out.png"
    assert main(["render", str(rec), "--png", str(out), "--model", "lite", "--skeleton"]) == 0
    assert _png_ok(out)


def test_render_jsonl_with_index(tmp_path, capsys):
    """JSON lines: --index picks a record (negative from the end); out of range → exit 2."""
    rec = tmp_path / "bodies.jsonl"
    rec.write_text("\n".join(json.dumps(_record(seq=s)) for s in range(3)) + "\n")
    out = tmp_path / "last.png"
    assert main(["render", str(rec), "--index", "-1", "--png", str(out), "--model", "lite", "--views", "top"]) == 0
    assert _png_ok(out)
    assert main(["render", str(rec), "--index", "3", "--png", str(out), "--model", "lite"]) == 2
    assert "out of range" in capsys.readouterr().err


@pytest.mark.parametrize(
    "mutate,message",
    [
        (lambda r: r.update(people=[]), "no people"),
        (lambda r: r["people"][0].update(pose_aa=[0.0] * 70), "pose_aa has 70 values"),
        (lambda r: r["people"][0].pop("transl_m"), "transl_m"),
        (lambda r: r["people"][0].update(betas=[float("nan")] + [0.0] * 9), "non-finite"),
    ],
)
def test_render_bad_records_are_one_line_errors(tmp_path, capsys, mutate, message):
    """Heartbeats, wrong lengths, missing fields, NaN → exit 2 with a one-line reason."""
    record = _record()
    mutate(record)
    rec = tmp_path / "bad.json"
    rec.write_text(json.dumps(record))
    assert main(["render", str(rec), "--png", str(tmp_path / "x.png"), "--model", "lite"]) == 2
    assert message in capsys.readouterr().err


def test_named_poses_are_distinct_and_grounded():
    """Every named pose is 72 finite numbers; upright ones carry +90° about x."""
    for name in POSES:
        p = pose_aa(name)
        assert p.shape == (72,) and np.isfinite(p).all()
    assert np.allclose(pose_aa("t_pose")[:3], [np.pi / 2, 0, 0])
    with pytest.raises(ValueError, match="unknown pose"):
        pose_aa("cartwheel")
