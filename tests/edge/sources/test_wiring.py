"""Wiring maps: line flips and swaps, tile placement, and clear errors."""

import numpy as np
import pytest

from edge.wiring import WiringMap


def test_line_operations():
    wire = np.arange(12).reshape(3, 4)
    assert (WiringMap.from_config({"flip_rows": True}, 3, 4).apply(wire) == wire[::-1]).all()
    assert (WiringMap.from_config({"flip_cols": True}, 3, 4).apply(wire) == wire[:, ::-1]).all()
    assert (WiringMap.from_config({"transpose": True}, 3, 4).apply(wire) == wire.T).all()
    swapped = WiringMap.from_config({"swap_odd_even_rows": True}, 3, 4).apply(wire)
    assert (swapped == wire[[1, 0, 2]]).all()


def test_tiles_sent_one_after_another_land_in_a_3x3_carpet():
    """The board sends nine 2×2 tiles stacked vertically (18×2); the carpet is 6×6."""
    carpet = np.arange(36).reshape(6, 6)
    tiles, wire_blocks = [], []
    for k in range(9):
        tr, tc = divmod(k, 3)
        block = carpet[2 * tr : 2 * tr + 2, 2 * tc : 2 * tc + 2]
        rot = k % 4
        wire_blocks.append(np.rot90(block, -rot))  # the board's tile is rotated; the map undoes it
        tiles.append({"wire": [2 * k, 0], "carpet": [2 * tr, 2 * tc], "size": [2, 2], "rot90": rot})
    wire = np.concatenate(wire_blocks)
    wmap = WiringMap.from_config({"tiles": tiles}, 18, 2)
    assert wmap.shape == (6, 6)
    np.testing.assert_array_equal(wmap.apply(wire), carpet)


def test_errors_name_the_problem():
    with pytest.raises(ValueError, match="unknown key.*flip_row.*accepted"):
        WiringMap.from_config({"flip_row": True}, 4, 4)
    two = [{"wire": [0, 0], "carpet": [0, 0], "size": [2, 4]}, {"wire": [2, 0], "carpet": [0, 0], "size": [2, 4]}]
    with pytest.raises(ValueError, match="overlaps"):
        WiringMap.from_config({"tiles": two}, 4, 4)
    with pytest.raises(ValueError, match="8 of the 16 wire samples"):
        WiringMap.from_config({"tiles": two[:1]}, 4, 4)
    hole = [two[0], {"wire": [2, 0], "carpet": [4, 0], "size": [2, 4]}]
    with pytest.raises(ValueError, match="uncovered"):
        WiringMap.from_config({"tiles": hole}, 4, 4)
    with pytest.raises(ValueError, match="leaves"):
        WiringMap.from_config({"tiles": [{"wire": [3, 0], "carpet": [0, 0], "size": [2, 4]}]}, 4, 4)
    with pytest.raises(ValueError, match="expects a 4×4"):
        WiringMap.identity(4, 4).apply(np.zeros((3, 4)))
