"""The carpet wire protocol: spec (protocol.toml, SPEC.md), Python codec, C reference, vectors, virtual device.

Standard library only.
"""
