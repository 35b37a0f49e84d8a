"""`ispm` and `gather` compute the caustic scenes' light on average (issue 29, item 3).

The ground truth is `path` plus, on caustic-ring, the light `path` cannot render: a point
light's caustic seen in the ring's mirror walls (light → mirror → floor → mirror → camera;
camera paths never reach the point light and light paths cannot connect to the camera
through a mirror). That light is computed independently by
`scripts/probe/caustic_breakdown.py`'s `ring_mirror_caustic` (the floor's light-traced radiance,
rendered top-down by `path`, read where the camera rays reflected by the ring land): 6.7% of
the image mean (48x48, 64M light paths), which is most of the "5% too bright" of the issue.
On cornell-glass the caustics seen through the glass sphere are missing from `path` too; there
the methods' excess over `path` on those pixels is under 1% of the image mean
(docs/bench/caustic_breakdown.md), inside the tolerance.
"""

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest

import gi

SCRIPTS = Path(__file__).resolve().parents[1] / "scripts" / "probe"
SIZE = (32, 32)


def ring_mirror_light(size: tuple) -> float:
    """caustic-ring's image mean of the light `path` misses in the mirror (see the module)."""
    sys.path.insert(0, str(SCRIPTS))
    try:
        spec = importlib.util.spec_from_file_location(
            "caustic_breakdown", SCRIPTS / "caustic_breakdown.py"
        )
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
    finally:
        sys.path.remove(str(SCRIPTS))
    missing, _ = module.ring_mirror_caustic(size, 4_000_000, map_size=256, rays=16)
    return float(missing.mean())


@pytest.mark.parametrize("name", ["caustic-ring", "cornell-glass"])
def test_ispm_and_gather_means_within_2_percent_of_path(name):
    # Defaults but the size (32x32) and seeds. Reference: `path` with 64 spp and 4M light
    # paths, whose image means differed by 0.1% (caustic-ring) and 0.3% (cornell-glass)
    # between seeds; the mirror light's map (4M light paths, 256²) gave 6.66% of the mean
    # against 6.59% at 16M and 512² (6.72% at 48x48 with 64M and 1024²). The methods' means
    # vary by 0.14-0.35% between seeds (sd over 4-6 seeds at 32x32), so 2 seeds and one
    # reference leave a standard error of about 0.35%: the 2% is over 5 of them.
    # Measured (mean / reference): caustic-ring ispm 1.008, gather 1.000; cornell-glass ispm
    # 1.008, gather 1.010 (the glass-seen caustics `path` misses are part of these ~1%).
    # Before the caustic photons were splatted at full resolution with kernels at least a
    # pixel wide, ispm on cornell-glass at 32x32 was 1.037 (sd 1.2% over 6 seeds: the glass
    # sphere's caustic, narrower than a pixel, read at pixel centres) and failed here.
    scene = gi.load_scene(name)
    ref = gi.render(scene, "path", size=SIZE, spp=64, light_paths=4_000_000, seed=100)
    target = float(ref.radiance.mean())
    if name == "caustic-ring":
        target += ring_mirror_light(SIZE)
    ratios = {
        method: np.mean(
            [gi.render(scene, method, size=SIZE, seed=s).radiance.mean() for s in (0, 1)]
        )
        / target
        for method in ("ispm", "gather")
    }
    print(name, ratios)
    for method, ratio in ratios.items():
        assert abs(ratio - 1) < 0.02, (name, method, ratio)
