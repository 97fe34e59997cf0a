"""Quantize the exported graphs with onnxruntime.quantization, and gate the result.

- encoder: ``quant_pre_process`` then per-channel static QDQ (uint8 activations, int8 weights),
  calibrated on simulated frames through :class:`FramesReader` (MinMax).
- head: dynamic int8 with uint8 weights (U8U8: no AVX2 U8S8 saturation) is measured against
  float; the head kept is dynamic when it is faster and costs ≤ ``head_tolerance_cm`` MPJPE,
  else float (≥ 10 % faster required: timing noise must not decide).
- gate: end-to-end MPJPE, int8 bundle vs fp32 bundle, must not grow by more than 0.3 cm. The
  QDQ encoder is judged in FAKE-QUANT mode: onnxruntime with graph optimisations off runs each
  QuantizeLinear/DequantizeLinear pair as float ops, so the number measures quantization, not
  the x86 U8S8 integer-kernel saturation an ARM board does not have (readout-and-edge.md). The
  same evaluation with the integer kernels is reported beside it, for information.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Callable

import numpy as np

GATE_CM = 0.3


def session(path: str | Path, threads: int = 1, optimise: bool = True):
    """An onnxruntime CPU session; ``optimise=False`` keeps QDQ pairs unfused (fake-quant mode)."""
    import onnxruntime as ort

    opts = ort.SessionOptions()
    opts.intra_op_num_threads = threads
    opts.inter_op_num_threads = 1
    opts.add_session_config_entry("session.intra_op.allow_spinning", "0")
    opts.graph_optimization_level = (ort.GraphOptimizationLevel.ORT_ENABLE_ALL if optimise
                                     else ort.GraphOptimizationLevel.ORT_DISABLE_ALL)
    opts.log_severity_level = 3
    return ort.InferenceSession(str(path), opts, providers=["CPUExecutionProvider"])


def _reader_class():
    from onnxruntime.quantization import CalibrationDataReader

    class FramesReader(CalibrationDataReader):
        """Feeds normalised frames (N,1,H,W) to the encoder's input in batches."""

        def __init__(self, frames: np.ndarray, input_name: str = "pressure", batch: int = 16):
            self.frames, self.input_name, self.batch = np.asarray(frames, np.float32), input_name, batch
            self.rewind()

        def get_next(self):
            if self.i >= len(self.frames):
                return None
            x = self.frames[self.i:self.i + self.batch]
            self.i += self.batch
            return {self.input_name: x}

        def rewind(self) -> None:
            self.i = 0

    return FramesReader


def preprocess(src: Path, dst: Path) -> Path:
    from onnxruntime.quantization.shape_inference import quant_pre_process

    try:
        quant_pre_process(str(src), str(dst), skip_symbolic_shape=False)
    except Exception:  # onnxruntime's symbolic shape inference misses some Concat patterns; ONNX's own suffices
        quant_pre_process(str(src), str(dst), skip_symbolic_shape=True)
    return dst


def quantize_encoder(encoder_fp32: str | Path, out: str | Path, calib_frames: np.ndarray, per_channel: bool = True) -> Path:
    """Static QDQ, per-channel int8 weights, uint8 activations, MinMax calibration on ``calib_frames``."""
    from onnxruntime.quantization import CalibrationMethod, QuantFormat, QuantType, quantize_static

    out = Path(out)
    pre = preprocess(Path(encoder_fp32), out.with_name(out.stem + ".pre.onnx"))
    try:
        quantize_static(str(pre), str(out), _reader_class()(calib_frames), quant_format=QuantFormat.QDQ,
                        per_channel=per_channel, activation_type=QuantType.QUInt8, weight_type=QuantType.QInt8,
                        calibrate_method=CalibrationMethod.MinMax)
    finally:
        pre.unlink(missing_ok=True)
    return out


def quantize_head_dynamic(head_fp32: str | Path, out: str | Path) -> Path:
    """Dynamic int8 of the head's MatMuls with uint8 weights (the variant that measured best)."""
    from onnxruntime.quantization import QuantType, quantize_dynamic

    out = Path(out)
    pre = preprocess(Path(head_fp32), out.with_name(out.stem + ".pre.onnx"))
    try:
        quantize_dynamic(str(pre), str(out), weight_type=QuantType.QUInt8)
    finally:
        pre.unlink(missing_ok=True)
    return out


def callables(encoder_sess, head_sess) -> tuple[Callable, Callable]:
    from export.model.heads import OUTPUTS

    names = [o.name for o in head_sess.get_outputs()]
    enc_in, head_in = encoder_sess.get_inputs()[0].name, head_sess.get_inputs()[0].name

    def encode(x: np.ndarray) -> np.ndarray:
        return encoder_sess.run(None, {enc_in: np.ascontiguousarray(x, np.float32)})[0]

    def head(w: np.ndarray) -> dict:
        out = dict(zip(names, head_sess.run(None, {head_in: np.ascontiguousarray(w, np.float32)})))
        return {k: out[k] for k in OUTPUTS}

    return encode, head


def latency_ms(sess, feed: dict[str, np.ndarray], repeats: int = 50, warmup: int = 5) -> float:
    """Median wall time of one run, milliseconds."""
    for _ in range(warmup):
        sess.run(None, feed)
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        sess.run(None, feed)
        times.append(time.perf_counter() - t)
    return float(np.median(times) * 1e3)


def quantize_and_gate(fp32: dict[str, Path], out_dir: str | Path, calib_frames: np.ndarray, tracks, window: int,
                      pitch_m: float, body, frame_stride: int = 2, head_tolerance_cm: float = 0.1,
                      gate_cm: float = GATE_CM, latency_repeats: int = 50) -> dict:
    """Quantize encoder (static QDQ) and head (dynamic uint8, kept only if it measures best), gate on MPJPE.

    Returns a report: paths of the int8 graphs, MPJPE fp32 / int8 (fake-quant) / int8 (x86 kernels),
    the head decision with its numbers, latencies (1 thread) and ``gate_passed``.
    """
    from export.evaluate import track_metrics

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    enc_q = quantize_encoder(fp32["encoder"], out / "encoder.int8.onnx", calib_frames)
    head_q = quantize_head_dynamic(fp32["head"], out / "head.int8.onnx")

    def mpjpe(enc_path, head_path, optimise_encoder=True):
        enc, head = callables(session(enc_path, optimise=optimise_encoder), session(head_path))
        return track_metrics(tracks, enc, head, window, pitch_m, body, frame_stride=frame_stride)

    m_fp32 = mpjpe(fp32["encoder"], fp32["head"])
    m_head_q = mpjpe(fp32["encoder"], head_q)
    feed_e = {"pressure": np.asarray(calib_frames[:1], np.float32)}
    feats = session(fp32["encoder"]).run(None, feed_e)[0]
    feed_h = {"features": np.repeat(feats[:, None], window, 1).astype(np.float32)}
    lat = {"encoder_fp32_ms": latency_ms(session(fp32["encoder"]), feed_e, latency_repeats),
           "encoder_int8_ms": latency_ms(session(enc_q), feed_e, latency_repeats),
           "head_fp32_ms": latency_ms(session(fp32["head"]), feed_h, latency_repeats),
           "head_int8_ms": latency_ms(session(head_q), feed_h, latency_repeats)}
    head_delta = m_head_q["mpjpe_cm"] - m_fp32["mpjpe_cm"]
    keep_dynamic = head_delta <= head_tolerance_cm and lat["head_int8_ms"] < 0.9 * lat["head_fp32_ms"]  # ≥ 10 % faster
    head_kept = head_q if keep_dynamic else Path(fp32["head"])
    m_fake = mpjpe(enc_q, head_kept, optimise_encoder=False)   # the gate: fake-quant QDQ encoder
    m_kernels = mpjpe(enc_q, head_kept, optimise_encoder=True)  # x86 integer kernels (information)
    delta = m_fake["mpjpe_cm"] - m_fp32["mpjpe_cm"]
    return {
        "encoder": str(enc_q), "head": str(head_kept), "head_quantization": "dynamic_uint8" if keep_dynamic else "float",
        "head_decision": {"dynamic_uint8_mpjpe_delta_cm": head_delta, "tolerance_cm": head_tolerance_cm,
                          "int8_ms": lat["head_int8_ms"], "fp32_ms": lat["head_fp32_ms"]},
        "mpjpe_fp32_cm": m_fp32["mpjpe_cm"], "mpjpe_int8_fake_quant_cm": m_fake["mpjpe_cm"],
        "mpjpe_int8_x86_kernels_cm": m_kernels["mpjpe_cm"], "gate_delta_cm": delta, "gate_cm": gate_cm,
        "gate_passed": bool(delta <= gate_cm), "gate_mode": "encoder QDQ in fake-quant (graph optimisations off); head as kept",
        "frames": m_fp32["frames"], "latency_1_thread": lat,
    }
