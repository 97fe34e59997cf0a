"""Helpers for the sink tests: a real mosquitto, a paho subscriber, record factories (see conftest.py)."""

from __future__ import annotations

import getpass
import math
import os
import shutil
import signal
import socket
import subprocess
import threading
import time
from pathlib import Path

import paho.mqtt.client as mqtt
import pytest

from edge.record import make_person, make_record

MOSQUITTO = shutil.which("mosquitto") or "/usr/sbin/mosquitto"
DEVICE = "carpet-01"
MODEL = "test-bundle@0123456789ab"


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_until(predicate, timeout_s: float, step_s: float = 0.01) -> bool:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(step_s)
    return bool(predicate())


class Broker:
    """One mosquitto process; stop() and start() again keep the port and the persistence."""

    def __init__(self, root: Path, users: dict[str, str] | None = None, tls: dict[str, str] | None = None) -> None:
        if not os.path.exists(MOSQUITTO):
            pytest.fail("mosquitto is not installed (looked for /usr/sbin/mosquitto): `make test` installs it "
                        "(apt-get install -y mosquitto); the MQTT sink tests need a real broker", pytrace=False)
        self.root = root
        self.port = free_port()
        self.log = root / "mosquitto.log"
        (root / "data").mkdir(parents=True)
        lines = [
            f"listener {self.port} 127.0.0.1",
            "persistence true",
            f"persistence_location {root / 'data'}/",
            "max_queued_messages 100000",
            "queue_qos0_messages true",
            f"log_dest file {self.log}",
            "log_type error",
            "log_type warning",
            "log_type notice",
            f"user {getpass.getuser()}",
        ]
        if users:
            pw = root / "passwd"
            for i, (user, password) in enumerate(users.items()):
                subprocess.run(["mosquitto_passwd", "-b"] + (["-c"] if i == 0 else []) + [str(pw), user, password],
                               check=True, capture_output=True, timeout=10)
            os.chmod(pw, 0o600)
            lines += ["allow_anonymous false", f"password_file {pw}"]
        else:
            lines += ["allow_anonymous true"]
        if tls:  # mutual TLS on the listener: cafile, certfile, keyfile
            lines += [f"{k} {v}" for k, v in tls.items()] + ["require_certificate true"]
        self.conf = root / "mosquitto.conf"
        self.conf.write_text("\n".join(lines) + "\n")
        self.proc: subprocess.Popen | None = None

    def start(self, timeout_s: float = 10.0) -> None:
        self.proc = subprocess.Popen([MOSQUITTO, "-c", str(self.conf)], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)

        def accepts() -> bool:
            if self.proc.poll() is not None:
                return True
            try:
                with socket.create_connection(("127.0.0.1", self.port), timeout=0.2):
                    return True
            except OSError:
                return False

        wait_until(accepts, timeout_s, 0.02)
        if self.proc.poll() is not None:
            err = self.proc.stderr.read().decode(errors="replace") if self.proc.stderr else ""
            pytest.fail(f"mosquitto did not start: {err}\n{self.log_tail()}", pytrace=False)

    def stop(self) -> None:
        if self.proc is not None and self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(timeout=5)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(timeout=5)
        self.proc = None

    def log_tail(self) -> str:
        return self.log.read_text(errors="replace")[-2000:] if self.log.exists() else ""

    def url(self, query: str = "", user: str = "", prefix: str = "cavatar") -> str:
        at = f"{user}@" if user else ""
        return f"mqtt://{at}127.0.0.1:{self.port}/{prefix}" + (f"?{query}" if query else "")


def brokers(folder: Path):
    """Generator for a pytest fixture: yields ``make(users=None, tls=None)`` → a started Broker in
    ``folder``; every broker made is stopped when the fixture ends. (The one factory every test folder uses.)"""
    made: list[Broker] = []

    def make(users: dict[str, str] | None = None, tls: dict[str, str] | None = None) -> Broker:
        b = Broker(folder / f"broker{len(made)}", users, tls)
        made.append(b)
        b.start()
        return b

    try:
        yield make
    finally:
        for b in made:
            b.stop()


class Subscriber:
    """A paho subscriber that records (topic, payload, retain, time) for every message."""

    def __init__(self, port: int, topics: list[str], client_id: str | None = None, persistent: bool = False,
                 username: str | None = None, password: str | None = None) -> None:
        self.messages: list[tuple[str, bytes, bool, float]] = []
        self.lock = threading.Lock()
        self.subscribed = threading.Event()
        self.topics = topics
        self.client = mqtt.Client(mqtt.CallbackAPIVersion.VERSION2, client_id=client_id or f"sub-{time.monotonic_ns()}",
                                  clean_session=not persistent)
        if username:
            self.client.username_pw_set(username, password)
        self.client.on_connect = self._on_connect
        self.client.on_message = self._on_message
        self.client.on_subscribe = lambda *a: self.subscribed.set()
        self.client.reconnect_delay_set(0.1, 0.2)  # type: ignore[arg-type]
        self.client.connect_async("127.0.0.1", port, keepalive=5)
        self.client.loop_start()
        assert self.subscribed.wait(10), "subscriber did not connect"

    def _on_connect(self, client, userdata, flags, reason_code, properties):
        if not reason_code.is_failure:
            client.subscribe([(t, 1) for t in self.topics])

    def _on_message(self, client, userdata, msg):
        with self.lock:
            self.messages.append((msg.topic, bytes(msg.payload), bool(msg.retain), time.monotonic()))

    def on(self, topic: str) -> list[tuple[bytes, bool]]:
        with self.lock:
            return [(p, r) for t, p, r, _ in self.messages if t == topic]

    def wait_for(self, topic: str, payload: bytes | None = None, timeout_s: float = 10.0) -> bool:
        return wait_until(lambda: any(payload is None or p == payload for p, _ in self.on(topic)), timeout_s)

    def close(self) -> None:
        self.client.disconnect()
        self.client.loop_stop()


def body_record(seq: int, people: int = 1, device: str = DEVICE, t0: float = 1_732_240_000.0) -> dict:
    """A realistic record: ``people`` persons with smooth, deterministic parameters."""
    persons = []
    for k in range(people):
        a = 0.01 * seq + k
        persons.append(make_person(
            track_id=k + 1,
            transl_m=[0.9 + 0.1 * math.sin(a), 0.9 + 0.1 * math.cos(a), 0.95],
            pose_aa=[0.1 * math.sin(a + j) for j in range(72)],
            betas=[0.01 * j for j in range(10)],
            confidence=0.9, activity="walking" if k % 2 == 0 else "squat"))
    return make_record(device, seq, t0 + seq / 14.0, MODEL, persons)


class Gate:
    """A TCP relay in front of the broker. Publishers connect through it; ``close()`` cuts
    every relayed connection and refuses new ones until ``open()``. Lets a test decide that
    the observer (connected to the broker directly) is back before the publishers are."""

    def __init__(self, target_port: int) -> None:
        self.target_port = target_port
        self.listener = socket.socket()
        self.listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self.listener.bind(("127.0.0.1", 0))
        self.listener.listen(16)
        self.port = self.listener.getsockname()[1]
        self.is_open = threading.Event()
        self.is_open.set()
        self.pairs: list[tuple[socket.socket, socket.socket]] = []
        self.lock = threading.Lock()
        self.stopped = False
        threading.Thread(target=self._accept, daemon=True).start()

    def _accept(self) -> None:
        while not self.stopped:
            try:
                conn, _ = self.listener.accept()
            except OSError:
                return
            if not self.is_open.is_set():
                conn.close()
                continue
            try:
                up = socket.create_connection(("127.0.0.1", self.target_port), timeout=2)
                up.settimeout(None)
            except OSError:
                conn.close()
                continue
            with self.lock:
                self.pairs.append((conn, up))
            threading.Thread(target=self._pump, args=(conn, up), daemon=True).start()
            threading.Thread(target=self._pump, args=(up, conn), daemon=True).start()

    @staticmethod
    def _pump(src: socket.socket, dst: socket.socket) -> None:
        try:
            while True:
                data = src.recv(65536)
                if not data:
                    break
                dst.sendall(data)
        except OSError:
            pass
        for s in (src, dst):
            try:
                s.shutdown(socket.SHUT_RDWR)
            except OSError:
                pass

    def close(self) -> None:
        self.is_open.clear()
        with self.lock:
            pairs, self.pairs = self.pairs, []
        for pair in pairs:
            for s in pair:
                try:
                    s.shutdown(socket.SHUT_RDWR)
                except OSError:
                    pass
                s.close()

    def open(self) -> None:
        self.is_open.set()

    def stop(self) -> None:
        self.stopped = True
        self.close()
        self.listener.close()


def make_certificates(folder: Path) -> dict[str, Path]:
    """A throwaway CA, a server certificate for 127.0.0.1 and a client certificate (openssl CLI)."""
    folder.mkdir(parents=True, exist_ok=True)
    if not shutil.which("openssl"):
        pytest.fail("openssl is not installed: apt-get install -y openssl (the TLS test makes its certificates with it)", pytrace=False)

    def run(*args: str) -> None:
        subprocess.run(["openssl", *args], cwd=folder, check=True, capture_output=True, timeout=60)

    run("req", "-x509", "-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:prime256v1", "-nodes", "-keyout", "ca.key",
        "-out", "ca.crt", "-days", "2", "-subj", "/CN=cavatar-test-ca")
    (folder / "san.ext").write_text("subjectAltName=IP:127.0.0.1,DNS:localhost\n")
    for name in ("server", "client"):
        run("req", "-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:prime256v1", "-nodes", "-keyout", f"{name}.key",
            "-out", f"{name}.csr", "-subj", f"/CN=cavatar-test-{name}")
        run("x509", "-req", "-in", f"{name}.csr", "-CA", "ca.crt", "-CAkey", "ca.key", "-CAcreateserial",
            "-out", f"{name}.crt", "-days", "2", "-extfile", "san.ext")
    return {p.stem + p.suffix.replace(".", "_"): folder / p.name for p in folder.iterdir()}
