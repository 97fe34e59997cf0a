"""Datasets of carpet frames with exact ground truth (see :mod:`sim.dataset.format`)."""

from sim.dataset.format import FAULT_BITS, FRAME_FLAGS, SCHEMA, SPLITS, Dataset, DatasetError, DatasetWriter, Subject

__all__ = ["Dataset", "DatasetError", "DatasetWriter", "Subject", "SCHEMA", "SPLITS", "FRAME_FLAGS", "FAULT_BITS"]
