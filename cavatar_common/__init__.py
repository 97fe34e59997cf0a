"""What several top-level packages share, kept low in the layering so none of them imports another.

design.md fixes who may import whom (firmware_protocol, calibration, edge, sim, export); errors,
provenance, the typed-config base and atomic file writes are used by all of them, so they live here,
one module each. This package imports the standard library only.
"""
