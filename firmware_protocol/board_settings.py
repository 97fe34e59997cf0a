"""What a virtual readout board is built with (:class:`BoardSettings`): grid, ADC, identity, timing, link.

Every physical setting is checked when the settings are made, with the accepted values in
the error; the values a board uses are resolved there too (default tiles, the packing's
name, sequence starts wrapped to their field widths). The fastest rate a board can scan
at follows from the settings (:attr:`BoardSettings.fastest_rate_hz`).
"""

from __future__ import annotations

import dataclasses

from firmware_protocol import codec

MASK32 = 0xFFFFFFFF
ADC_BITS = (8, 10, 12, 16)
PACKING_MAX_BITS = {"u8": 8, "packed12": 12, "u16": 16}
ROW_HEADER_BYTES = 18  # a ROW packet without its samples (type, seq, frame_seq, t_us, row, count, packing, CRC)
FRAME_END_BYTES = 23  # a FRAME_END packet (type, seq, frame_seq, t_us, rows, scan_time_us, frame_crc32, CRC)


def wire_len(nbytes: int) -> int:
    """Bytes on the wire for a packet of ``nbytes`` before COBS (overhead and delimiter)."""
    return nbytes + nbytes // 254 + 2


@dataclasses.dataclass(frozen=True)
class BoardSettings:
    """A virtual board's settings, checked and resolved (see the :mod:`firmware_protocol.virtual_board` docstring).

    ``tile_rows``/``tile_cols`` None: 32×32 tiles where the grid allows, else one tile.
    ``packing`` is given as a name or its code and held as its name. ``protocol_version``/
    ``definition_hash`` None: this codec's; others make a board built from another protocol
    definition (INFO carries them, and definition-seeded packets are CRC'd with that hash),
    to test that a host refuses it loudly.
    """

    rows: int = 96
    cols: int = 96
    _: dataclasses.KW_ONLY
    tile_rows: int | None = None
    tile_cols: int | None = None
    adc_bits: int = 12
    packing: str | int = "packed12"
    sign: int = -1
    rate_hz: float = 14.0
    device_id: str = "virtual-carpet"
    fw_version: tuple[int, int, int] = (1, 0, 0)
    has_temperature: bool = True
    temperature_c: float = 24.0
    has_gain: bool = True
    gain_steps: int = 128
    gain_step: int = 64
    seed: int = 0
    row_time_us: float = 100.0
    min_rate_hz: float = 0.5
    max_rate_hz: float = 100.0
    link_bytes_per_s: float | None = None
    tx_buffer_bytes: int = 1 << 20
    status_interval_s: float = 1.0
    t_us_start: int = 0
    frame_seq_start: int = 0
    seq_start: int = 0
    autostart: bool = False
    bus_powered: bool = True
    protocol_version: int | None = None
    definition_hash: int | None = None

    def __post_init__(self) -> None:
        packing_name, tile_rows, tile_cols = _check_physical(self)
        resolved = {
            "packing": packing_name, "tile_rows": tile_rows, "tile_cols": tile_cols,
            "fw_version": tuple(self.fw_version), "row_time_us": float(self.row_time_us),
            "t_us_start": self.t_us_start & MASK32, "frame_seq_start": self.frame_seq_start & MASK32,
            "seq_start": self.seq_start & 0xFFFF,
            "protocol_version": codec.PROTOCOL_VERSION if self.protocol_version is None else self.protocol_version,
            "definition_hash": codec.DEFINITION_HASH if self.definition_hash is None else self.definition_hash,
        }
        for name, value in resolved.items():
            object.__setattr__(self, name, value)  # frozen: resolved once, here
        _check_rates(self)

    @property
    def packing_code(self) -> int:
        """The packing's code on the wire."""
        return codec.PACKING[str(self.packing)]

    @property
    def full_scale(self) -> int:
        """The highest ADC reading (samples are clamped to 0..full_scale)."""
        return (1 << self.adc_bits) - 1

    @property
    def row_wire_bytes(self) -> int:
        """A ROW packet of ``cols`` samples before COBS."""
        return ROW_HEADER_BYTES + codec.packed_size(self.cols, self.packing_code)

    @property
    def frame_wire_bytes(self) -> int:
        """A whole frame (every ROW and its FRAME_END) on the wire."""
        return self.rows * wire_len(self.row_wire_bytes) + wire_len(FRAME_END_BYTES)

    @property
    def scan_time_s(self) -> float:
        """The time to sample every row once."""
        return self.rows * self.row_time_us * 1e-6

    @property
    def fastest_rate_hz(self) -> float:
        """The fastest rate ``max_rate_hz``, the scan and the link (if ``link_bytes_per_s``) allow."""
        limits = [self.max_rate_hz, 1.0 / self.scan_time_s]
        if self.link_bytes_per_s:
            limits.append(self.link_bytes_per_s / self.frame_wire_bytes)
        return min(limits)

    @property
    def rate_mhz(self) -> int:
        """``rate_hz`` as SET_RATE and INFO carry it (mHz)."""
        return int(round(self.rate_hz * 1000))

    def rate_ok(self, rate_mhz: int) -> bool:
        """Whether the board can scan at ``rate_mhz``."""
        return self.min_rate_hz * 1000 - 1e-9 <= rate_mhz <= self.fastest_rate_hz * 1000 + 1e-9


def _check_physical(s: BoardSettings) -> tuple[str, int, int]:
    """Grid, ADC, packing, sign, tiles and identity checked, with the accepted values in the error.

    Returns (packing name, tile rows, tile cols).
    """
    rows, cols, packing = s.rows, s.cols, s.packing
    if rows < 1 or cols < 1 or rows > 0xFFFF or cols > 0xFFFF:
        raise ValueError(f"rows and cols must be 1..65535; got {rows}x{cols}")
    if s.adc_bits not in ADC_BITS:
        raise ValueError(f"adc_bits must be one of {ADC_BITS}; got {s.adc_bits}")
    packing_name = codec.PACKING_NAMES.get(packing, packing) if isinstance(packing, int) else packing
    if packing_name not in PACKING_MAX_BITS:
        raise ValueError(f"packing must be one of {sorted(codec.PACKING)} (or its code); got {packing!r}")
    if s.adc_bits > PACKING_MAX_BITS[packing_name]:
        raise ValueError(f"packing {packing_name} holds at most {PACKING_MAX_BITS[packing_name]} bits; "
                         f"adc_bits={s.adc_bits}")
    if s.sign not in (-1, 1):
        raise ValueError(f"sign must be -1 (pressure lowers the reading) or +1 (raises it); got {s.sign}")
    tile_rows = s.tile_rows if s.tile_rows is not None else (rows // 32 if rows % 32 == 0 else 1)
    tile_cols = s.tile_cols if s.tile_cols is not None else (cols // 32 if cols % 32 == 0 else 1)
    if not (1 <= tile_rows <= 255 and 1 <= tile_cols <= 255) or rows % tile_rows or cols % tile_cols:
        raise ValueError(f"tiles {tile_rows}x{tile_cols} must be 1..255 and divide the grid {rows}x{cols}")
    _check_identity(s.device_id, s.fw_version)
    return str(packing_name), tile_rows, tile_cols


def _check_identity(device_id: str, fw_version: tuple[int, int, int]) -> None:
    """The device id and firmware version INFO carries fit their fields."""
    try:
        device_id.encode("ascii")
    except UnicodeEncodeError:
        raise ValueError(f"device_id must be ASCII; got {device_id!r}") from None
    if not 1 <= len(device_id) <= 16:
        raise ValueError(f"device_id must be 1..16 ASCII characters; got {device_id!r}")
    if len(fw_version) != 3 or not all(0 <= v <= 255 for v in fw_version):
        raise ValueError(f"fw_version must be (major, minor, patch), each 0..255; got {fw_version!r}")


def _check_rates(s: BoardSettings) -> None:
    """A ROW fits a packet, and ``rate_hz`` is one the scan and the link allow."""
    if s.row_wire_bytes > codec.SPEC.max_packet_bytes:
        raise ValueError(f"a ROW of {s.cols} samples in {s.packing} takes {s.row_wire_bytes} bytes "
                         f"> max_packet_bytes={codec.SPEC.max_packet_bytes}")
    if not s.rate_ok(s.rate_mhz):
        raise ValueError(f"rate_hz={s.rate_hz} is outside {s.min_rate_hz}..{s.fastest_rate_hz:.3f} Hz for this board")
