"""The runtime's setup: everything loaded and checked before the first output exists.

Order (:meth:`RuntimeSetup.setup`): the seq ledger beside the status file (a second runtime on the
same file is refused before it touches the board), the model bundle, the source, the calibration,
the source started, the board held against bundle and calibration, the status folder, the sinks
last, so that a refusal leaves no output behind. Every refusal is a :class:`SetupError` that names
the fix (the key or flag to change).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable

from edge.runtime.carpet_calibration import ChosenCalibration, check_board, choose_calibration
from edge.runtime.config import RuntimeConfig
from edge.runtime.counters import Counters, StageTimes
from edge.runtime.errors import SetupError
from edge.runtime.publisher import Publisher
from edge.runtime.stages import FrameStages
from edge.sources.base import FrameSource, require_frame_source

if TYPE_CHECKING:
    from edge.infer.bundle import ModelBundle
    from edge.runtime.events import EventStage
    from edge.runtime.seq import SeqLedger


def load_bundle(path: Path, threads: int) -> ModelBundle:
    """The model bundle at ``path``, its hashes checked; SetupError when it does not match its manifest."""
    from edge.infer import BundleError, ModelBundle

    try:
        return ModelBundle.load(path, threads=threads)
    except BundleError as exc:
        raise SetupError(f"model bundle refused: {exc}. The runtime never runs a bundle that does not match its "
                         "manifest; reinstall the package for the shipped bundle, or point [model] bundle "
                         "(--bundle DIR) at an intact bundle folder written by `cavatar bundle`.") from None


def check_board_fits(bundle: ModelBundle, chosen: ChosenCalibration, info: Any) -> tuple[int, int]:
    """The board's grid (rows, cols), once the bundle's grid, the calibration and the bundle's pitch all fit it.

    ``info``: the board's INFO as the source reports it (rows, cols, device id, bit depth)."""
    grid = (int(info.rows), int(info.cols))
    if tuple(bundle.grid) != grid:
        raise SetupError(f"the model bundle {bundle.folder} is for a {bundle.grid[0]}×{bundle.grid[1]} "
                         f"carpet; this board is {grid[0]}×{grid[1]}. Use a bundle exported for this grid "
                         "([model] bundle, --bundle DIR).")
    check_board(chosen, info)
    cal = chosen.calibration
    if abs(cal.pitch_m - bundle.pitch_m) > 0.05 * bundle.pitch_m:
        raise SetupError(f"this carpet's pitch is {cal.pitch_m * 1e3:.2f} mm (calibration), the model bundle was "
                         f"trained at {bundle.pitch_m * 1e3:.2f} mm; use a bundle trained for this pitch.")
    return grid


def check_status_writable(status: Path) -> None:
    """Make the status file's folder; SetupError when the folder or the file cannot be written by this user."""
    try:
        status.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise SetupError(f"status file {status}: cannot create its folder ({exc}); set [runtime] status_file "
                         "(--status-file) to a writable place") from None
    if not os.access(status.parent, os.W_OK) or (status.exists() and not os.access(status, os.W_OK)):
        raise SetupError(f"status file {status}: not writable by this user; set [runtime] status_file "
                         "(--status-file) to a writable place")


def open_sinks(urls: list[str], device_id: str) -> list:
    """Every sink of ``urls`` opened, or none: one that fails closes those already open (SetupError)."""
    from edge.sinks import SinkError, open_sink, redact

    sinks: list = []
    for url in urls:
        try:
            sinks.append(open_sink(url, device=device_id))
        except (SinkError, ValueError, OSError) as exc:
            for s in sinks:
                s.close()
            raise SetupError(f"sink {redact(url)}: {exc}") from None
    return sinks


def previous_seq(status_path: Path, device_id: str) -> int:
    """The last seq a previous run with this status file published (-1: none), so seq keeps increasing."""
    from edge.runtime.status import StatusFileError, read_status

    if not status_path.exists():
        return -1
    try:
        old = read_status(status_path)
    except StatusFileError:
        return -1
    last = (old.get("publish") or {}).get("last_seq")
    if old.get("device") == device_id and isinstance(last, int) and last >= 0:
        return last
    return -1


class RuntimeSetup:
    """The setup half of :class:`edge.runtime.loop.Runtime` (a mixin): what it reads and what it makes."""

    config: RuntimeConfig
    clock: Callable[[], float]
    say: Callable[[str], None]
    times: StageTimes
    counters: Counters
    invalid: Counters
    state: str
    source: FrameSource | None
    sinks: list | None
    bundle: ModelBundle | None
    chosen: ChosenCalibration | None
    stages: FrameStages | None
    events: EventStage | None
    publisher: Publisher | None
    seqs: SeqLedger | None
    _seq_start: int

    def setup(self) -> None:
        """Load and check everything; open the sinks last, so a refusal leaves no output behind. SetupError."""
        from edge.runtime.seq import SeqLedger, SeqLedgerBusy, SeqLedgerError

        status = self.config.status_path()
        ledger = SeqLedger(status, self.config.device.id)
        try:  # first: a second runtime on this status file is refused before it touches the board
            self._seq_start = ledger.open(at_least=previous_seq(status, self.config.device.id) + 1)
        except (SeqLedgerBusy, SeqLedgerError) as exc:
            raise SetupError(str(exc)) from None
        except OSError as exc:
            raise SetupError(f"status file {status}: cannot be written, nor its seq ledger beside it ({exc}); set [runtime] "
                             "status_file (--status-file) to a writable place") from None
        self.seqs = ledger
        try:
            self._setup()
        except BaseException:
            ledger.discard()
            self.seqs = None
            raise

    def _setup(self) -> None:
        """Bundle, source, calibration, frame stages, sinks, publisher and events, in that order; state 'ready'."""
        from edge.runtime.reader import open_timed_source
        from edge.sources import SourceError

        cfg = self.config
        if self.source is not None:  # also one set after construction (tests): held to the same interface
            self.source = require_frame_source(self.source)
        if self.bundle is None:
            self.bundle = load_bundle(cfg.bundle_path(), cfg.model.threads)
        if self.source is None:
            try:
                self.source = open_timed_source(cfg.source.url, self.times, queue_frames=cfg.source.queue_frames,
                                                missing_rows=cfg.source.missing_rows)
            except (ValueError, SourceError) as exc:
                raise SetupError(f"source {cfg.source.url}: {exc}") from None
        if self.chosen is None:  # before the source starts: the virtual carpet's session takes seconds
            self.chosen = choose_calibration(cfg.calibration.file, cfg.source.url, cfg.output_dir(), self.say)
        try:
            self.source.start()
        except (SourceError, OSError, ValueError) as exc:
            raise SetupError(f"source {cfg.source.url} did not start: {exc}") from None
        try:
            self.stages = self._frame_stages(self.source.info, self.bundle, self.chosen)
            check_status_writable(cfg.status_path())
            if self.sinks is None:
                self.sinks = open_sinks(cfg.sinks.urls, cfg.device.id)
        except BaseException:
            self.source.stop()
            raise
        self.publisher = Publisher(self.sinks, counters=self.counters, times=self.times,
                                   queue_records=cfg.sinks.queue_records, clock=self.clock)
        if cfg.events.enabled:
            from edge.runtime.events import EventStage

            self.events = EventStage(cfg.events, cfg.device.id, self.chosen.calibration.pitch_m, self.times,
                                     clock=self.clock)
        self.state = "ready"

    def _frame_stages(self, info: Any, bundle: ModelBundle, chosen: ChosenCalibration) -> FrameStages:
        """The per-frame stages (calibrate → scene → infer → record) for this board, once it fits bundle and calibration."""
        from calibration.runtime import CalibratedFrames
        from edge.scene import SceneTracker

        cfg = self.config
        grid = check_board_fits(bundle, chosen, info)
        cal = chosen.calibration
        calibrated = CalibratedFrames(cal, info, baseline=cfg.calibration.baseline)
        scene = SceneTracker(grid[0], grid[1], cal.pitch_m, cfg.scene)
        return FrameStages(calibrated, scene, bundle, device=cfg.device.id, times=self.times,
                           counters=self.counters, invalid=self.invalid,
                           heartbeat_s=cfg.runtime.heartbeat_s, seq_start=self._seq_start,
                           resolve_heading=cfg.model.resolve_heading,
                           heading_params=cfg.model.heading_params or None)


__all__ = ["RuntimeSetup", "check_board_fits", "check_status_writable", "load_bundle", "open_sinks", "previous_seq"]
