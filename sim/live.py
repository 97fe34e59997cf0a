"""The virtual carpet, live: simulated people → contact → sensor, one frame at a time.

``LiveCarpet(rows, cols, people, seed)(k)`` returns frame k's raw counts (frames are
made in order; going back restarts the world). Motion is generated in chunks of
``chunk_s`` seconds, one activity per person each (each chunk a new scene: the same
people, other activities and places; with several people, lying activities are left
out — they do not fit together on the carpet), so the stream runs as long as asked. ``truth(k)`` gives the people's true
SMPL parameters for frame k (the demo draws them beside the reconstruction).

This is what ``sim://`` streams through the real wire protocol.
"""

from __future__ import annotations

import numpy as np

from sim.dataset.generate import LYING, PAPER_ACTIVITIES


def live_sensor(seed: int, grid: int = 96, adc_bits: int = 12, pitch_mm: float = 19.05):
    """The sensor of ``sim://?seed=…&grid=…&bits=…&pitch_mm=…`` (the runtime calibrates this same carpet)."""
    from sim.sensor import CarpetSensor

    return CarpetSensor.random(seed, grid=grid, adc_bits=adc_bits, pitch_mm=pitch_mm)


class LiveCarpet:
    def __init__(self, rows: int = 96, cols: int = 96, people: int = 1, seed: int = 0, pitch_mm: float = 19.05,
                 rate_hz: float = 14.0, adc_bits: int = 12, chunk_s: float = 10.0, body: str = "lite",
                 activities: tuple[str, ...] = PAPER_ACTIVITIES + ("walking",)) -> None:
        from edge.body import BodyModel
        from sim.contact import ContactModel, subject_mass_kg, tissue_stiffness
        from sim.motion import Subject

        if rows != cols or rows not in (96, 48, 32):
            raise ValueError(f"the simulated carpet is 96×96, 48×48 or 32×32; got {rows}×{cols}")
        if not 0 <= people <= 3:
            raise ValueError(f"people must be 0..3, got {people}")
        self.rows, self.cols, self.people, self.seed = rows, cols, people, seed
        self.pitch_m, self.rate_hz = pitch_mm / 1000, rate_hz
        self.chunk_frames = max(1, int(round(chunk_s * rate_hz)))
        self.activities = activities
        self.body = BodyModel.load(body)
        self.contact = ContactModel(rows, cols, pitch_m=self.pitch_m)
        self.tissue = tissue_stiffness(self.body)
        self.subjects = [Subject.random(i, seed * 1000 + i) for i in range(people)]
        self.mass_kg = [subject_mass_kg(self.body, s.betas) for s in self.subjects]
        self.sensor = live_sensor(seed, rows, adc_bits, pitch_mm)
        self.sign = int(self.sensor.config.frontend.sign)
        self.adc_bits = int(self.sensor.config.frontend.adc_bits)
        self._scene = None
        self._scene_chunk = -1
        self._next = 0
        self.truth(0)  # place the first scene now, so the first frame is as quick as the others

    def _chunk(self, chunk: int):
        if chunk != self._scene_chunk:
            from sim.dataset.generate import place_scene
            from sim.motion import scene

            rng = np.random.default_rng((self.seed, chunk))
            size = self.rows * self.pitch_m
            pool = [a for a in self.activities if len(self.subjects) < 2 or a not in LYING]
            seconds = self.chunk_frames / self.rate_hz
            for attempt in range(6):  # activities that do not fit together: draw others
                acts = [[str(rng.choice(pool))] for _ in self.subjects]
                try:
                    self._scene = place_scene(scene, self.subjects, acts, seconds, self.rate_hz, size, (self.seed, chunk, attempt),
                                              self.body, attempts=2)
                    break
                except ValueError:
                    if attempt == 5:
                        raise
            self._scene_chunk = chunk
        return self._scene

    def truth(self, k: int) -> list[dict]:
        """True SMPL parameters of the people in frame k."""
        if not self.subjects:
            return []
        sc = self._chunk(k // self.chunk_frames)
        t = min(k % self.chunk_frames, sc.num_frames - 1)
        return [{"subject_id": tr.subject_id, "pose_aa": tr.pose_aa[t], "betas": tr.betas, "transl_m": tr.transl_m[t],
                 "activity": tr.activity_names[t]} for tr in sc.tracks]

    def pressure_kpa(self, k: int) -> np.ndarray:
        total = np.zeros((self.rows, self.cols), np.float32)
        for person, mass in zip(self.truth(k), self.mass_kg):
            v = self.body.forward(person["pose_aa"][None], person["betas"][None], person["transl_m"][None], vertices=True)
            res = self.contact.pressure_kpa(v["vertices"][0], self.body.faces, mass, static=True, tissue_kpa_per_mm=self.tissue)
            total += res.pressure_kpa
        return total

    def __call__(self, k: int) -> np.ndarray:
        if k < self._next:  # going back: restart the sensor's state
            self.sensor.start_session(0)
        self._next = k + 1
        return self.sensor.counts(self.pressure_kpa(k), k / self.rate_hz)
