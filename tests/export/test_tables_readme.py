"""The README's model table: one overall row per protocol, regenerated between its markers."""

import json

import pytest

from export.tables import README_BEGIN, README_END, main, protocols_markdown, replace_block


def overall(mpjpe, model=None):
    o = {"frames": 100, "mpjpe_cm": mpjpe, "pa_mpjpe_cm": 4.0, "local_mpjpe_cm": 6.0, "heading_median_deg": 10.0,
         "heading_over45_pct": 12.0, "heading_over90_pct": 9.0, "pve_cm": 15.0, "transl_cm": 8.0}
    if model is not None:
        o.update(model_mpjpe_cm=model, model_heading_median_deg=20.0, model_heading_over45_pct=22.0,
                 model_heading_over90_pct=19.0)
    return o


def test_rows_per_protocol_with_the_models_own_heading_and_the_baseline():
    md = protocols_markdown({"unseen": {"overall": overall(13.5, 14.7), "baseline": overall(31.0)},
                             "seen-time": {"overall": overall(9.0)}})
    rows = md.strip().splitlines()
    assert len(rows) == 2 + 4 and all(r.count("|") == 12 for r in rows)
    assert rows[2].startswith("| unseen | model alone | 100 | 14.70 |") and "| 19.00 |" in rows[2]
    assert rows[3].startswith("| unseen | resolved from the feet | 100 | 13.50 |")
    assert rows[4].startswith("| unseen | mean pose at CoP (baseline) | 100 | 31.00 |")
    assert rows[5].startswith("| seen-time | model alone | 100 | 9.00 |")


def test_the_block_is_replaced_between_its_markers_and_nothing_else(tmp_path):
    text = f"before\n{README_BEGIN}\nold\n{README_END}\nafter\n"
    assert replace_block(text, "new\n") == f"before\n{README_BEGIN}\nnew\n{README_END}\nafter\n"
    with pytest.raises(ValueError, match="block"):
        replace_block("no markers", "x")
    readme, res = tmp_path / "README.md", tmp_path / "u.json"
    readme.write_text(text)
    res.write_text(json.dumps({"overall": overall(13.5), "setup": {"subjects": ["s01"], "frame_stride": 2}}))
    assert main(["--readme", str(readme), f"unseen={res}"]) == 0
    out = readme.read_text()
    assert out.startswith("before\n") and out.endswith(f"{README_END}\nafter\n") and "old" not in out and "| unseen |" in out
    assert main(["--readme", str(readme), "nonsense"]) == 2
    assert main(["--readme", str(tmp_path / "none.md"), f"unseen={res}"]) == 2
