"""Consume a CAvatar carpet's body stream: drop duplicates, turn each person into 3D joints.

    python docs/examples/subscriber.py --host 127.0.0.1 --prefix cavatar --device carpet-01
    python docs/examples/subscriber.py --host broker.lan --user reader --json --count 100

Needs the runtime package (paho-mqtt, numpy, `edge.body`); the broker password, if any, comes
from $CAVATAR_MQTT_PASSWORD. What it shows (docs/record-schema.md describes every field):

- QoS 1 is at-least-once: around a reconnect a record can arrive twice. Records are told
  apart by (device, seq), so a repeat is dropped; a jump in seq is a loss, counted.
- Heartbeats (``"people": []``) say the runtime is alive and the carpet empty.
- A record carries SMPL parameters, not joints: ``edge.body.BodyModel.forward`` turns
  ``pose_aa``, ``betas`` and ``transl_m`` into 24 joints in metres in the carpet frame
  (z up; joint 0, the pelvis, is ``transl_m``). Joint names: ``edge.body.SMPL_JOINT_NAMES``.

One line per person (``--json``: one JSON object per person), a summary on stderr at the end.
"""

from __future__ import annotations

import argparse
import json
import os
import queue
import sys
from collections import OrderedDict
from typing import Any, Iterator

import numpy as np


class Deduplicator:
    """(device, seq) seen recently → drop; per device, a jump in seq counts the records missed."""

    def __init__(self, window: int = 4096) -> None:
        self.window = window
        self._seen: OrderedDict[tuple[str, int], None] = OrderedDict()
        self._highest: dict[str, int] = {}
        self.duplicates = 0
        self.missed = 0

    def fresh(self, record: dict[str, Any]) -> bool:
        key = (str(record["device"]), int(record["seq"]))
        if key in self._seen:
            self.duplicates += 1
            return False
        self._seen[key] = None
        if len(self._seen) > self.window:
            self._seen.popitem(last=False)
        device, seq = key
        top = self._highest.get(device)
        if top is not None and seq > top + 1:
            self.missed += seq - top - 1
        if top is None or seq > top:
            self._highest[device] = seq
        return True


def people_joints(record: dict[str, Any], model: Any) -> list[dict[str, Any]]:
    """Every person of a ``cavatar.bodies/1`` record with its joints: (24, 3) metres, carpet frame, SMPL order."""
    people = record["people"]
    if not people:
        return []
    out = model.forward(np.array([p["pose_aa"] for p in people]), np.array([p["betas"] for p in people]),
                        np.array([p["transl_m"] for p in people]))
    return [{"device": record["device"], "seq": record["seq"], "time": record["time"], "track_id": p["track_id"],
             "activity": p["activity"], "confidence": p["confidence"], "joints_m": joints}
            for p, joints in zip(people, out["joints"])]


def messages(args: argparse.Namespace, topic: str) -> Iterator[bytes]:
    """Payloads of ``topic`` (QoS 1) until --count or --timeout ends the iteration's consumer."""
    import paho.mqtt.client as mqtt

    inbox: queue.Queue = queue.Queue()
    client = mqtt.Client(mqtt.CallbackAPIVersion.VERSION2, client_id=args.client_id or "", clean_session=True)
    if args.user:
        client.username_pw_set(args.user, os.environ.get("CAVATAR_MQTT_PASSWORD"))

    def on_connect(c: Any, userdata: Any, flags: Any, rc: Any, props: Any) -> None:
        if rc.is_failure:
            print(f"the broker refused the connection: {rc}", file=sys.stderr, flush=True)
        else:
            c.subscribe(topic, qos=1)

    client.on_connect = on_connect
    client.on_subscribe = lambda *a: print(f"listening on {topic}", file=sys.stderr, flush=True)
    client.on_message = lambda c, u, msg: inbox.put(bytes(msg.payload))
    client.connect_async(args.host, args.port, keepalive=30)
    client.loop_start()
    try:
        while True:
            try:
                yield inbox.get(timeout=args.timeout)
            except queue.Empty:
                return
    finally:
        client.disconnect()
        client.loop_stop()


def line(person: dict[str, Any], names: tuple[str, ...]) -> str:
    j = person["joints_m"]
    head = j[names.index("head")]
    return (f"{person['device']} seq {person['seq']} track {person['track_id']}: {person['activity']} "
            f"(confidence {person['confidence']:.2f}), pelvis ({j[0][0]:.2f}, {j[0][1]:.2f}, {j[0][2]:.2f}) m, "
            f"head {head[2]:.2f} m above the floor")


def main(argv: list[str] | None = None) -> int:
    from edge.body import SMPL_JOINT_NAMES, BodyModel
    from edge.topics import DeviceTopics

    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--host", default="127.0.0.1")
    p.add_argument("--port", type=int, default=1883)
    p.add_argument("--user", help="broker user (password from $CAVATAR_MQTT_PASSWORD)")
    p.add_argument("--prefix", default="cavatar")
    p.add_argument("--device", default="carpet-01")
    p.add_argument("--client-id", default="")
    p.add_argument("--body-model", default="lite", help="'lite', 'full' or an SMPL-layout file")
    p.add_argument("--count", type=int, default=0, help="stop after this many distinct records (0: never)")
    p.add_argument("--timeout", type=float, default=3600.0, help="stop after this many seconds without a message")
    p.add_argument("--json", action="store_true", help="one JSON object per person (joints by name)")
    args = p.parse_args(argv)

    model = BodyModel.load(args.body_model)
    dedup = Deduplicator()
    records = bad = 0
    for payload in messages(args, DeviceTopics(args.prefix, args.device).bodies):
        try:
            record = json.loads(payload)
            if record.get("schema") != "cavatar.bodies/1":
                raise ValueError(f"schema {record.get('schema')!r}")
            if not dedup.fresh(record):
                continue
            people = people_joints(record, model)
        except (ValueError, KeyError, TypeError) as exc:  # garbage on the wire: counted and skipped
            bad += 1
            print(f"skipped a message that is not a body record: {exc}", file=sys.stderr)
            continue
        records += 1
        for person in people:
            if args.json:
                joints = {name: [round(float(v), 4) for v in xyz] for name, xyz in zip(SMPL_JOINT_NAMES, person["joints_m"])}
                print(json.dumps({**person, "joints_m": joints}), flush=True)
            else:
                print(line(person, SMPL_JOINT_NAMES), flush=True)
        if args.count and records >= args.count:
            break
    print(f"{records} records, {dedup.duplicates} duplicates dropped, {dedup.missed} missed (gaps in seq), "
          f"{bad} unreadable", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
