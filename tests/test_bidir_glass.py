"""Issue 44 item 4: `bidir` behind glass, on `tests/scenes/openings/glass_room.json` (a
ceiling panel over a floating glass slab; the floor under the slab is lit only through the
glass).

Before, the light of an emitter or a sun through glass onto a surface the camera sees
(L S+ D E) had one estimator in `bidir`: the camera paths of `specular_paths` that sample the
floor's BSDF towards the glass and hit the panel by chance (4 a pixel), so the floor under
the slab was fireflies on black: its median 0.28-0.32 of `path`'s, its mean 0.91-1.22 with
the seed. Now those paths are the delta-chain light tracer's (`specular_paths::caustics`,
`chain_only`: from the emitters and suns, connected to the camera at the first non-delta
vertex after delta lobes alone), and the camera paths leave them out
(`path::radiance_past_delta_chain`). Measured after (seeds 1-4): under the slab mean
0.95-0.98, median 0.92-0.95 of `path`.

The whole frame is compared with `path` at the same `max_depth` 5: at the default depth
`bidir`'s light subpaths run out of VPL slots at high orders (0.984 of `path` at depth 8,
0.94 at 64; 0.973 without the slab), which is the subpath budget's matter, not the glass's.
Measured at depth 5: 0.993.
"""

from pathlib import Path

import numpy as np
import pytest
from test_sky_openings import under_glass

import gi

DIR = Path(__file__).parent / "scenes" / "openings"


@pytest.fixture(scope="module")
def glass():
    return gi.load_scene(DIR / "glass_room.json")


def test_floor_under_the_glass_is_lit_through_it(glass):
    # Reference: `path` 2048 spp (tests/scenes/openings/glass_room-full.json). Tolerances:
    # the region's mean within 8% (ispm's bound in test_sky_openings.py) and the median of
    # the pixel ratios within 12% (one frame's noise; fireflies on black gave 0.28-0.32).
    ref = gi.read_image(DIR / "glass_room-full.exr")[..., :3].mean(-1)
    for seed in (1, 2):
        r = gi.render(glass, "bidir", seed=seed)
        region = under_glass(r)
        assert region.sum() > 100
        img = r.radiance[..., :3].mean(-1)
        mean = img[region].mean() / ref[region].mean()
        median = np.median(img[region] / ref[region])
        print(seed, mean, median)
        assert abs(mean - 1) < 0.08, (seed, mean)
        assert abs(median - 1) < 0.12, (seed, median)


def test_frame_matches_path_at_the_same_depth(glass):
    # `path` 256 spp at depth 5 (its mean's noise about 0.3%); `bidir` seeds 1-2 at 5%, the
    # issue's tolerance for `bidir`.
    ref = gi.render(glass, "path", spp=256, seed=9, max_depth=5).radiance[..., :3].mean()
    for seed in (1, 2):
        mean = gi.render(glass, "bidir", seed=seed, max_depth=5).radiance[..., :3].mean()
        print(seed, mean / ref)
        assert abs(mean / ref - 1) < 0.05, (seed, mean / ref)
