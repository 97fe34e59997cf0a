"""The shipped bundle loads, and every file its manifest lists is packaged (a pip install must not lose one:
the runtime refuses a bundle with a listed file missing)."""

from __future__ import annotations

import configparser
import fnmatch
import json
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]


def test_every_file_of_the_shipped_bundle_is_package_data():
    cfg = configparser.ConfigParser()
    cfg.read(ROOT / "setup.cfg")
    patterns = [p.strip() for p in cfg["options.package_data"]["edge.models"].split(",")]
    bundles = sorted((ROOT / "edge" / "models").glob("*/manifest.json"))
    assert bundles
    for manifest in bundles:
        names = ["manifest.json", "manifest.json.sha256", *json.loads(manifest.read_text())["files"]]
        for name in names:
            rel = f"{manifest.parent.name}/{name}"
            assert any(fnmatch.fnmatch(rel, p) for p in patterns), f"{rel} is not in setup.cfg's edge.models package_data"


def test_the_default_bundle_loads_and_fits_the_default_carpet():
    from edge.infer import ModelBundle
    from edge.runtime.config import default_bundle_path

    b = ModelBundle.load(default_bundle_path(), grid=(96, 96))
    assert b.window == 40 and b.manifest["schema"] == "cavatar.bundle/1"
