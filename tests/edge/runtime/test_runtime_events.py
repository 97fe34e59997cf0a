"""The runtime raises fall and person-down events on the virtual carpet and clears them when it stops."""

from dataclasses import replace

from runtime_helpers import read_jsonl, sim_url

from edge.runtime import Runtime


def test_a_simulated_fall_raises_events_in_the_runtime_and_stopping_clears_them(config, tmp_path):
    cfg = config(people=1, source=sim_url(1, activities="fall_backward", scene_s=12))
    cfg = replace(cfg, events=replace(cfg.events, person_down_s=3.0))
    final = Runtime(cfg, say=lambda text: None).run_for(frames=int(12 * 14))
    events = read_jsonl(tmp_path / "bodies.events.jsonl")
    assert all(e["schema"] == "cavatar.events/1" and e["device"] == cfg.device.id for e in events)
    raised = [(e["type"], e["track_id"]) for e in events if e["state"] == "raised"]
    assert [k for k, _ in raised] == ["fall", "person_down"]
    cleared = [(e["type"], e["reason"]) for e in events if e["state"] == "cleared"]
    assert sorted(cleared) == [("fall", "stopped"), ("person_down", "stopped")]  # nothing left standing
    bodies = read_jsonl(tmp_path / "bodies.jsonl")
    assert bodies and all(r["schema"] == "cavatar.bodies/1" for r in bodies)  # events never mix into the bodies
    assert final["stages_ms"]["events"]["n"] > 0


def test_outcome_callbacks_run_with_events_switched_off(config):
    """on_outcome (cavatar score's capture, the demo's truth) must not depend on [events] enabled."""
    cfg = config(people=1)
    cfg = replace(cfg, events=replace(cfg.events, enabled=False))
    rt = Runtime(cfg, say=lambda text: None)
    outcomes = []
    rt.on_outcome.append(outcomes.append)
    rt.run_for(frames=20)
    assert rt.events is None
    assert len(outcomes) == 20 and all(o is not None for o in outcomes)
