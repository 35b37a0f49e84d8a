"""`gather`'s default image against the `path` reference (issue 46, item 8: "gather at 200k
photons is blotchy with streaks across the boxes").

The blotches are each footprint's photon noise. Footprints now hold a set number of photons
(240 at smoothing 1, the paper's range) whatever the scene and photon count; before, they
held what the photon differentials gave (~120 in `cornell`). The error is the relative MSE
of both images box-filtered 3×3 (the blotches, a few pixels wide here, stay; most of the
pixel noise of 4 samples goes), against tests/data/cornell-path-128.exr (`path`, 1024 spp,
scripts/data/gather_reference.py).

Measured at 128×128, 4 spp, 200k photons, seeds 1 and 2: 0.00301 and 0.00313 now; 0.00422
and 0.00441 with the old footprints (main at 5a1a0f1). The bound, 0.0036, is 15% above the
new figures and 15% below the old ones.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import gi

REFERENCE = Path(__file__).parent / "data" / "cornell-path-128.exr"
BOUND = 0.0036


def box3(img: np.ndarray) -> np.ndarray:
    p = np.pad(img, ((1, 1), (1, 1), (0, 0)), mode="edge")
    h, w = img.shape[:2]
    return sum(p[y : y + h, x : x + w] for y in range(3) for x in range(3)) / 9.0


def blotch_error(img: np.ndarray, ref: np.ndarray) -> float:
    a, b = box3(img), box3(ref)
    return float(np.mean((a - b) ** 2 / (b**2 + 0.01)))


@pytest.mark.parametrize("seed", [1, 2])
def test_default_gather_image_is_within_the_blotch_bound(seed: int) -> None:
    ref = gi.read_image(str(REFERENCE))
    # The defaults (200k photons, smoothing 1, cone kernel) at a test's size and spp.
    img = gi.render("cornell", "gather", size=(128, 128), spp=4, seed=seed).radiance
    err = blotch_error(img, ref)
    assert err < BOUND, f"relMSE of the 3x3-filtered image {err:.5f} (bound {BOUND})"
    # The footprints' bias stays small: the image mean within 1% of the reference's.
    assert abs(img.mean() / ref.mean() - 1.0) < 0.01
