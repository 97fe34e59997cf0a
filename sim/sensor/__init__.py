"""Sensor model of the synthetic carpet: true pressure (kPa) per sensel → raw counts.

Usage::

    import numpy as np
    from sim.sensor import CarpetSensor, FrameStream, StreamConfig, true_pressure_estimate

    sensor = CarpetSensor.random(seed=7, grid=96)          # carpet drawn from the note's ranges
    p = np.zeros(sensor.shape); p[40:52, 30:36] = 30.0      # kPa
    counts = sensor.counts(p, t_s=0.0)                      # (96, 96) uint16
    truth = sensor.last                                     # saturation mask, state, noiseless reading
    est = true_pressure_estimate(counts, sensor.params, truth.state)   # inverse with the true params
    masks = sensor.fault_masks                              # {"dead": bool (H,W), ...}

    stream = FrameStream(sensor, StreamConfig(drop_rate=0.01, duplicate_rate=0.01, tear_rate=0.005))
    for counts, t_s, flags in stream.frames(pressure_frames): ...

See ``docs/sim-sensor.md`` for the pipeline and every parameter.
"""

from .config import (
    ADC_BITS,
    CrosstalkConfig,
    DynamicsConfig,
    FrontEndConfig,
    GainConfig,
    GridConfig,
    NoiseConfig,
    ResponseConfig,
    SensorConfig,
    SessionConfig,
    StreamConfig,
    lsb10_to_counts,
)
from .fault_config import FaultConfig, LineFault, MuxBankFault, ShortFault
from .inverse import InverseResult, initial_state, true_pressure_estimate
from .model import CarpetSensor, FrameState, FrameTruth
from .params import FAULT_KINDS, CarpetParams, SensorParams, SessionParams, hill, hill_inverse
from .ranges import FAULT_RATES, RANGES
from .stream import FrameFlags, FrameStream

__all__ = [
    "ADC_BITS", "FAULT_KINDS", "FAULT_RATES", "RANGES",
    "CarpetParams", "CarpetSensor", "CrosstalkConfig", "DynamicsConfig", "FaultConfig", "FrameFlags",
    "FrameState", "FrameStream", "FrameTruth", "FrontEndConfig", "GainConfig", "GridConfig", "InverseResult",
    "LineFault", "MuxBankFault", "NoiseConfig", "ResponseConfig", "SensorConfig", "SensorParams",
    "SessionConfig", "SessionParams", "ShortFault", "StreamConfig",
    "hill", "hill_inverse", "initial_state", "lsb10_to_counts", "true_pressure_estimate",
]
