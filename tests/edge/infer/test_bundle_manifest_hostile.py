"""The manifest is protected: hashed in a sidecar, its paths confined to the bundle, its values checked
(issue 18, finding 7). Every refusal is one BundleError line, never a traceback at run time."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

pytest.importorskip("onnx")

from test_bundle_loading import make_bundle  # noqa: E402

from edge.infer import BundleError, ModelBundle  # noqa: E402
from edge.infer.bundle import SIDECAR, seal_manifest, sha256_file, write_manifest  # noqa: E402
from edge.runtime.config import default_bundle_path  # noqa: E402


def edit(folder: Path, change) -> dict:
    m = json.loads((folder / "manifest.json").read_text())
    change(m)
    (folder / "manifest.json").write_text(json.dumps(m))  # as an attacker edits it: no new sidecar
    return m


def test_an_edited_manifest_is_refused_by_its_sidecar(tmp_path):
    folder = make_bundle(tmp_path / "b")
    edit(folder, lambda m: m["input"]["normalisation"].update(scale_kpa=0))
    with pytest.raises(BundleError, match="edited or damaged") as err:
        ModelBundle.load(folder)
    assert "\n" not in str(err.value)


def test_a_manifest_without_its_sidecar_is_refused(tmp_path):
    folder = make_bundle(tmp_path / "b")
    (folder / SIDECAR).unlink()
    with pytest.raises(BundleError, match="unprotected"):
        ModelBundle.load(folder)


@pytest.mark.parametrize("name", ["/etc/shadow", "../outside.onnx", "sub/dir.onnx", "manifest.json.sha256"])
def test_listed_paths_must_stay_inside_the_bundle(tmp_path, name):
    folder = make_bundle(tmp_path / "b")
    (tmp_path / "outside.onnx").write_bytes(b"x")
    m = json.loads((folder / "manifest.json").read_text())
    m["files"][name] = "0" * 64
    write_manifest(folder, m)  # even a manifest sealed by its author
    with pytest.raises(BundleError, match="files"):
        ModelBundle.load(folder)


def test_a_listed_file_that_is_a_link_is_refused(tmp_path):
    folder = make_bundle(tmp_path / "b")
    secret = tmp_path / "secret"
    secret.write_bytes(b"secret")
    (folder / "extra.bin").symlink_to(secret)
    m = json.loads((folder / "manifest.json").read_text())
    m["files"]["extra.bin"] = sha256_file(secret)
    write_manifest(folder, m)
    with pytest.raises(BundleError, match="extra.bin is a link"):
        ModelBundle.load(folder)


@pytest.mark.parametrize("key,value,says", [
    ("input.normalisation.scale_kpa", 0, "scale_kpa"),
    ("input.normalisation.scale_kpa", "1", "scale_kpa"),
    ("grid", ["x", 96], "grid"),
    ("grid", [0, 96], "grid"),
    ("grid", [100000, 100000], "grid"),
    ("pitch_m", -0.01, "pitch_m"),
    ("window", 10**9, "window"),
    ("activities", "walking", "activities"),
    ("name", "../../x", "name"),
])
def test_bad_values_are_one_clear_line(tmp_path, key, value, says):
    folder = make_bundle(tmp_path / "b")
    m = json.loads((folder / "manifest.json").read_text())
    *path, last = key.split(".")
    target = m
    for k in path:
        target = target[k]
    target[last] = value
    write_manifest(folder, m)
    with pytest.raises(BundleError, match=f"values out of range: .*{says}") as err:
        ModelBundle.load(folder)
    assert "\n" not in str(err.value)


def test_the_shipped_bundle_is_sealed(tmp_path):
    folder = tmp_path / "lean"
    shutil.copytree(default_bundle_path(), folder)
    ModelBundle.load(folder, grid=(96, 96))
    m = (folder / "manifest.json").read_text()
    (folder / "manifest.json").write_text(m.replace('"scale_kpa": 1.0', '"scale_kpa": 0.0'))
    with pytest.raises(BundleError, match="edited or damaged"):
        ModelBundle.load(folder)
    seal_manifest(folder)  # the owner's deliberate edit, sealed: now the value check speaks
    with pytest.raises(BundleError, match="scale_kpa"):
        ModelBundle.load(folder)
