# Stitching of a grid of tiles cut in numpy from one generated texture at known positions.
import numpy as np
import pytest

import fvm
from synthetic import texture


def test_stitch_recovers_known_tile_positions():
    # 2 x 3 tiles of 120 x 160 px at a nominal 25 % overlap (steps 120 px in x, 90 px in y), each off its
    # nominal place by a few whole pixels as a stage would put it. Registration finds sub-pixel offsets; on
    # integer shifts of one noise-free texture it must land within 0.05 px (the sub-pixel refinement's settling
    # tolerance), which a wrong peak (tens of px) or a half-pixel bias fails.
    rng = np.random.default_rng(9)
    scene = texture(rng, 260, 440, grain_px=1.5)
    rows, cols, th, tw = 2, 3, 120, 160
    jitter = rng.integers(-4, 5, (rows * cols, 2))
    jitter[0] = 0
    truth, tiles, layout = [], [], []
    for r in range(rows):
        for c in range(cols):
            k = r * cols + c
            x, y = 10 + c * 120 + jitter[k, 0], 10 + r * 90 + jitter[k, 1]
            truth.append((x - 10, y - 10))
            tiles.append(scene[y:y + th, x:x + tw])
            layout.append((r, c))
    result = fvm.stitch(tiles, layout, overlap=0.25)
    assert result["accepted"] == 7 and all(result["registered"])  # 4 right and 3 lower neighbours
    np.testing.assert_allclose(result["positions"], np.array(truth, dtype=float), atol=0.05)


def test_stitch_refuses_a_layout_without_two_neighbours():
    # Holes are allowed (a region that is not a rectangle); tiles of which no two are neighbours are not.
    tile = np.zeros((32, 32))
    with pytest.raises(fvm.InputError, match="no two tiles are neighbours"):
        fvm.stitch([tile, tile], [(0, 0), (1, 1)])
