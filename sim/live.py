"""The virtual carpet, live: simulated people → contact → sensor, one frame at a time.

``LiveCarpet(rows, cols, people, seed)(k)`` returns frame k's raw counts (frames are
made in order; going back restarts the world). Motion is generated in chunks of at least
``chunk_s`` seconds, one activity per person each (each chunk a new scene: the same people,
other activities and places; with several people, lying activities are left out — they do
not fit together on the carpet), so the stream runs as long as asked. A chunk
lasts longer where its activity needs it at the person's own tempo (a push-up or a sit-up
~17–19 s, sitting ~10 s; ``sim.motion.scene(extend=True)``, as datasets are made); with
``extend=False`` every chunk lasts exactly ``chunk_s`` and such activities are squeezed into it.
``locate(k)`` gives frame k's chunk; ``truth(k)`` the people's true SMPL parameters for frame k
(the demo draws them beside the reconstruction).

This is what ``sim://`` streams through the real wire protocol.

Placing a scene (motion for every person, fitted onto the carpet, retried when they do not
fit) takes 0.3 s to several seconds; done when the stream reaches it, a real-time stream
stops for that long every chunk. ``prefetch=True`` (what ``sim://`` at speed > 0 uses)
places the NEXT chunk's scene in one helper process (multiprocessing, spawned, so it is safe
beside threads; one job at a time) while the current chunk streams, so the stream does not
wait unless placing takes longer than a chunk. The scene is the same either way (a pure
function of seed, chunk and people: :func:`place_chunk`). A helper that dies or cannot start
is not replaced: scenes are then placed here again, as without prefetch (logged once).
``close()`` ends the helper; so do garbage collection and the interpreter's exit.
"""

from __future__ import annotations

import bisect
import logging
import multiprocessing
import weakref

import numpy as np

from sim.dataset.generate import LYING, PAPER_ACTIVITIES

log = logging.getLogger(__name__)

HELPER_TIMEOUT_S = 120.0  # longest wait for the helper's scene before placing it here instead


def live_sensor(seed: int, grid: int = 96, adc_bits: int = 12, pitch_mm: float = 19.05):
    """The sensor of ``sim://?seed=…&grid=…&bits=…&pitch_mm=…`` (the runtime calibrates this same carpet)."""
    from sim.sensor import CarpetSensor

    return CarpetSensor.random(seed, grid=grid, adc_bits=adc_bits, pitch_mm=pitch_mm)


def place_chunk(subjects, activities, seed: int, chunk: int, seconds: float, rate_hz: float, size_m: float, extend: bool,
                body):
    """The scene of chunk ``chunk``: one activity per person drawn from ``activities`` (lying ones left out
    with several people), placed on a ``size_m`` carpet; other activities are drawn when they do not fit
    (extend: the scene lasts as long as its activities need, at least ``seconds``)."""
    from sim.dataset.generate import place_scene
    from sim.motion import scene
    from sim.motion.falls import SCENARIOS, scenario_scene

    rng = np.random.default_rng((seed, chunk))
    pool = [a for a in activities if len(subjects) < 2 or (a not in LYING and a not in SCENARIOS)]
    for attempt in range(6):  # activities that do not fit together: draw others
        acts = [[str(rng.choice(pool))] for _ in subjects]
        if acts[0][0] in SCENARIOS:  # a fall or a look-alike (sim.motion.falls): one person
            return scenario_scene(subjects[0], acts[0][0], seconds, rate_hz, size_m, (seed, chunk, attempt), body)
        try:
            return place_scene(scene, subjects, acts, seconds, rate_hz, size_m, (seed, chunk, attempt), body, attempts=2,
                               extend=extend)
        except ValueError:
            if attempt == 5:
                raise


def _helper_main(conn, body_name: str) -> None:
    """The helper process: (chunk, place_chunk args) in, (chunk, ok, scene or exception) out, until EOF or None."""
    from edge.body import BodyModel

    body = BodyModel.load(body_name)
    while True:
        try:
            job = conn.recv()
        except (EOFError, OSError):
            return
        if job is None:
            return
        chunk, args = job
        try:
            reply = (chunk, True, place_chunk(*args, body))
        except Exception as exc:  # e.g. people that do not fit: the caller raises the same in-process
            reply = (chunk, False, exc)
        try:
            conn.send(reply)
        except (EOFError, OSError):
            return


class _SceneHelper:
    """One spawned process that places the next chunk's scene; at most one job at a time."""

    def __init__(self, body_name: str) -> None:
        ctx = multiprocessing.get_context("spawn")
        self._conn, child = ctx.Pipe()
        self._proc = ctx.Process(target=_helper_main, args=(child, body_name), name="live-carpet-scenes", daemon=True)
        self._proc.start()
        child.close()  # so that our end reads EOF if the helper dies
        self.pending: int | None = None  # the chunk being placed
        self.failed = False

    def ahead(self, chunk: int, args) -> None:
        """Have ``chunk`` placed next, unless it already is or a stale job still runs (tried again next frame)."""
        if self.failed or self.pending == chunk:
            return
        if self.pending is not None:
            try:
                if not self._conn.poll(0):
                    return
                self._conn.recv()  # the stale job's scene: not needed any more
            except (EOFError, OSError) as exc:
                return self._fail(exc)
            self.pending = None
        try:
            self._conn.send((chunk, args()))
        except (EOFError, OSError, ValueError) as exc:
            return self._fail(exc)
        self.pending = chunk

    def take(self, chunk: int, timeout_s: float):
        """The scene of ``chunk`` (waiting up to ``timeout_s``), or None: then the caller places it."""
        try:
            if not self._conn.poll(timeout_s):
                raise TimeoutError(f"no scene within {timeout_s:g} s")
            got, ok, value = self._conn.recv()
        except (EOFError, OSError, TimeoutError) as exc:
            return self._fail(exc)
        self.pending = None
        return value if ok and got == chunk else None

    def _fail(self, why: BaseException) -> None:
        log.warning("live carpet: the scene helper process stopped (%r); scenes are placed in-process again", why)
        self.failed = True
        self.close()

    def close(self) -> None:
        try:
            self._conn.close()
        except OSError:
            pass
        if self._proc.is_alive():
            self._proc.terminate()
        self._proc.join(2.0)


class LiveCarpet:
    def __init__(self, rows: int = 96, cols: int = 96, people: int = 1, seed: int = 0, pitch_mm: float = 19.05,
                 rate_hz: float = 14.0, adc_bits: int = 12, chunk_s: float = 10.0, body: str = "lite",
                 activities: tuple[str, ...] = PAPER_ACTIVITIES + ("walking",), prefetch: bool = False,
                 extend: bool = True) -> None:
        from edge.body import BodyModel
        from sim.contact import ContactModel, regional_tissue, subject_mass_kg
        from sim.contact.segments import SegmentMassModel
        from sim.motion import Subject

        if rows != cols or rows not in (96, 48, 32):
            raise ValueError(f"the simulated carpet is 96×96, 48×48 or 32×32; got {rows}×{cols}")
        if not 0 <= people <= 3:
            raise ValueError(f"people must be 0..3, got {people}")
        self.rows, self.cols, self.people, self.seed = rows, cols, people, seed
        self.pitch_m, self.rate_hz = pitch_mm / 1000, rate_hz
        self.chunk_frames = max(1, int(round(chunk_s * rate_hz)))  # the least (extend) or exact length of a chunk
        self.extend = extend
        self._starts = [0]  # first frame of each chunk known so far (extend: chunks differ in length)
        self.activities = activities
        self.body_name = body
        self.body = BodyModel.load(body)
        self.contact = ContactModel(rows, cols, pitch_m=self.pitch_m)
        self.tissue = regional_tissue(self.body)
        self.subjects = [Subject.random(i, seed * 1000 + i) for i in range(people)]
        self.mass_kg = [subject_mass_kg(self.body, s.betas) for s in self.subjects]
        self.mass_models = [SegmentMassModel(self.body, s.betas) for s in self.subjects]  # COM independent of pose
        self.sensor = live_sensor(seed, rows, adc_bits, pitch_mm)
        self.sign = int(self.sensor.config.frontend.sign)
        self.adc_bits = int(self.sensor.config.frontend.adc_bits)
        self._scene = None
        self._scene_chunk = -1
        self._next = 0
        self.scenes_from_helper = 0  # scenes the helper placed (the rest were placed here)
        self._helper = _SceneHelper(body) if prefetch and self.subjects else None
        if self._helper is not None:
            self._finalizer = weakref.finalize(self, self._helper.close)
        self.truth(0)  # place the first scene now, so the first frame is as quick as the others

    def _chunk_args(self, chunk: int) -> tuple:
        return (self.subjects, self.activities, self.seed, chunk, self.chunk_frames / self.rate_hz, self.rate_hz,
                self.rows * self.pitch_m, self.extend)

    def _chunk(self, chunk: int):
        helper = self._helper
        if chunk != self._scene_chunk:
            scene = None
            if helper is not None and helper.pending == chunk:
                scene = helper.take(chunk, HELPER_TIMEOUT_S)
                self.scenes_from_helper += scene is not None
            if scene is None:
                scene = place_chunk(*self._chunk_args(chunk), self.body)
            self._scene, self._scene_chunk = scene, chunk
        if helper is not None:  # keep the next scene coming (a no-op on most frames)
            helper.ahead(chunk + 1, lambda: self._chunk_args(chunk + 1))
        return self._scene

    def close(self) -> None:
        """End the helper process, if any."""
        if self._helper is not None:
            self._finalizer()  # _SceneHelper.close, once
            self._helper = None

    def __enter__(self) -> "LiveCarpet":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def locate(self, k: int) -> tuple[int, int]:
        """(chunk, frame within it) of frame k. With extend the chunks before k are placed to learn their
        lengths (they are anyway, as the stream reaches k)."""
        if not self.extend or not self.subjects:
            return divmod(k, self.chunk_frames)
        i = bisect.bisect_right(self._starts, k) - 1
        while True:
            n = self._chunk(i).num_frames
            if k < self._starts[i] + n:
                return i, k - self._starts[i]
            if i + 1 == len(self._starts):
                self._starts.append(self._starts[i] + n)
            i += 1

    def truth(self, k: int) -> list[dict]:
        """True SMPL parameters of the people in frame k ("scene": the chunk it belongs to)."""
        if not self.subjects:
            return []
        chunk, t = self.locate(k)
        sc = self._chunk(chunk)
        t = min(t, sc.num_frames - 1)
        return [{"subject_id": tr.subject_id, "pose_aa": tr.pose_aa[t], "betas": tr.betas, "transl_m": tr.transl_m[t],
                 "activity": tr.activity_names[t], "scene": chunk} for tr in sc.tracks]

    def pressure_kpa(self, k: int) -> np.ndarray:
        total = np.zeros((self.rows, self.cols), np.float32)
        for person, mass, mm in zip(self.truth(k), self.mass_kg, self.mass_models):
            v = self.body.forward(person["pose_aa"][None], person["betas"][None], person["transl_m"][None], vertices=True)
            com = mm.com_m(person["pose_aa"][None], person["transl_m"][None])[0]
            res = self.contact.pressure_kpa(v["vertices"][0], self.body.faces, mass, com_m=com, static=True,
                                            tissue_kpa_per_mm=self.tissue)
            total += res.pressure_kpa
        return total

    def __call__(self, k: int) -> np.ndarray:
        if k < self._next:  # going back: restart the sensor's state
            self.sensor.start_session(0)
        self._next = k + 1
        return self.sensor.counts(self.pressure_kpa(k), k / self.rate_hz)
