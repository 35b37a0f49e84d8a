"""Issue 44 item 4: light through glass from every kind of source, in `ispm`, `bidir` and
`direct`, against `path` (the scenes of `tests/glass_scenes.py` at 64×48; references:
`scripts/data/glass_sources_references.py`, 2048 spp, committed beside the openings scenes).

The region is the one the source lights only through the glass (the floor under the slab;
the inside of the glazed room). The table over 160×120 and four seeds is
`docs/bench/glass-sources.md` (`scripts/bench/glass_sources.py`).

- `ispm` traces every source's photons through the glass on the CPU (point and spot lights'
  aimed at it, the others' by power) and keeps glass opaque in its shadow maps: measured
  0.955–1.015 of `path` behind the glass over every source (160×120, seeds 1–4).
- `bidir`: the light through glass is the delta-chain light tracer's (emitters, suns) and the
  camera paths' (sky, point lights' light tracer); the light it then reflects is the VPLs'.
- `direct` is the direct light alone: nothing passes the glass (as `path` at depth 1).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from glass_scenes import KINDS, behind, scene

import gi

DIR = Path(__file__).parent / "scenes" / "openings"
SEEDS = (1, 2)


def reference(kind: str) -> np.ndarray:
    meta = json.loads((DIR / f"glass-{kind}.json").read_text())
    assert meta["spp"] >= 2048
    assert meta["behind_stderr"] / meta["behind"] < 0.01, meta
    return gi.read_image(DIR / f"glass-{kind}.exr")[..., :3].mean(-1)


def region_ratios(kind: str, method: str) -> list[float]:
    """Each seed's mean over the region, over the reference's there."""
    s, ref = scene(kind, 64, 48), reference(kind)
    out = []
    for seed in SEEDS:
        r = gi.render(s, method, seed=seed)
        region = behind(kind, r)
        assert region.sum() > 50
        out.append(float(r.radiance[..., :3].mean(-1)[region].mean() / ref[region].mean()))
    print(kind, method, out)
    return out


@pytest.mark.parametrize("kind", KINDS)
def test_ispm_light_through_glass_matches_path(kind):
    # The 5% for an `ispm` frame, each seed; 7% under the sky alone, whose photons
    # through the window are few (~2% of them: its frame's spread over seeds is 4%,
    # `test_sky_openings.py`'s strict xfail, issue 44 item 3). Measured at 64x48, seeds 1-2:
    # 0.977-1.003 (window-sky 0.954, 1.017).
    ratios = region_ratios(kind, "ispm")
    tolerance = 0.07 if kind == "window-sky" else 0.05
    assert np.all(np.abs(np.array(ratios) - 1) < tolerance), ratios


UNSTABLE = {
    "window-area": "bidir's VPLs of an emitter outside a glazed window: half its 64 light "
    "subpaths are now aimed at the pane (frame/bidir/glass_aim.rs), but the room's light "
    "rests on the vertices right after the glass, which have no MIS partner and no clamp "
    "(likely their 1/d^2 spikes: 4x the VPLs cut the spread only 1.4x): region "
    "0.79-1.11 of path's over seeds 1-6 at 64x48 (mean 0.92; 4x the VPLs: 0.89-1.08); "
    "before the aiming 1.16, 1.28 at seeds 1-2",
    "window-sky": "bidir's VPLs of the sky through a glazed window: half its 64 light "
    "subpaths are now aimed through the pane's box (frame/bidir/glass_aim.rs; before, a "
    "VPL got in in rare frames: 2.87, 0.37 at seeds 1-2); the VPL part still varies, "
    "region 0.79-1.36 of path's over seeds 1-6 at 64x48 (mean 1.00): few of the aimed "
    "sky photons' directions enter, and the vertices right after the glass have no MIS "
    "partner and no clamp",
}


@pytest.mark.parametrize(
    "kind",
    [
        pytest.param(k, marks=pytest.mark.xfail(strict=True, reason=UNSTABLE[k]))
        if k in UNSTABLE
        else k
        for k in KINDS
    ],
)
def test_bidir_light_through_glass_matches_path(kind):
    # The mean of seeds 1-2 within 8%, each seed within 15%: one `bidir` frame's mean varies
    # by ±4.5% between seeds without glass (issue 48's per-frame factor, its VPLs), more in
    # a region of ~100 pixels. Measured at 64x48: slab-point 1.129, 0.971; slab-area 0.994,
    # 1.012; window-point 0.994, 1.016.
    ratios = np.array(region_ratios(kind, "bidir"))
    assert abs(ratios.mean() - 1) < 0.08, ratios
    assert np.all(np.abs(ratios - 1) < 0.15), ratios


@pytest.mark.parametrize("kind", ["slab-point", "slab-area", "window-sun", "window-sky"])
def test_direct_leaves_light_through_glass_out(kind):
    # `direct` is `path` at depth 1, which no light through glass reaches (a reference at
    # depth 1 is zero there): under 1% of the full light, so the shadow maps keep the glass
    # opaque and nothing is counted twice in the methods that add the caustic paths.
    s, ref = scene(kind, 64, 48), reference(kind)
    r = gi.render(s, "direct", seed=1)
    region = behind(kind, r)
    ratio = r.radiance[..., :3].mean(-1)[region].mean() / ref[region].mean()
    print(kind, ratio)
    assert ratio < 0.01, ratio


def test_bidir_sky_through_glazing_is_steady():
    """The sky's light through a glazed window at `max_depth` 3 (the sky seen through the
    pane from the room's surfaces; no VPL gets inside at that depth): before, the bundles'
    sky control variate (`bidir.wgsl`) added the sky's unshadowed light in closed form and
    took 16 bundles' samples of it away, a difference that is zero on average in a closed
    room but ±100% of the sky's light per frame: the region's mean 0.03, 0.93, −0.44, 2.51
    of `path`'s (seeds 1-4, 64x48). Its coefficient is now the share of sky the visible
    surfaces see (`frame/bidir/sky_share.rs`, 0 here): 1.21, 1.04, 1.07, 1.13. Bounds: 25%
    each and a spread of 20% (the +4-21% left is not explained: the camera paths through
    the pane against `path`'s at the same depth)."""
    s = scene("window-sky", 64, 48)
    ref = gi.render(s, "path", spp=256, seed=5, max_depth=3)
    region = behind("window-sky", ref)
    b = ref.radiance[..., :3].mean(-1)[region].mean()
    ratios = []
    for seed in (1, 2, 3, 4):
        r = gi.render(s, "bidir", seed=seed, max_depth=3)
        ratios.append(float(r.radiance[..., :3].mean(-1)[behind("window-sky", r)].mean() / b))
    print(ratios)
    assert np.all(np.abs(np.array(ratios) - 1) < 0.25), ratios
    assert max(ratios) - min(ratios) < 0.2, ratios


def test_bidir_sun_through_glazing_is_steady():
    # Per-seed region means within 5% of each other (seeds 1-2): the 2% for a frame,
    # loosened for a region. The means pass test_bidir_light_through_glass_matches_path.
    # Before the sun's light subpaths were aimed at the pane (frame/bidir/glass_aim.rs)
    # ~2 of its 64 got in: 0.977, 0.889 here (160x120 seeds 1-4: 0.897-1.261). Now
    # 1.001, 0.975; seeds 1-6 0.975-1.049 (mean 1.017, sd 0.025).
    ratios = np.array(region_ratios("window-sun", "bidir"))
    assert ratios.max() - ratios.min() < 0.05 * ratios.mean(), ratios
