"""Issue 44 items 3-4: the sky through an opening and light through glass in the GPU
direct light (`direct`, `ispm`), against `path` references (tests/scenes/openings,
`scripts/data/openings_references.py`: 2048-4096 spp at 96x72, the mean's standard error
under 0.2%).

window_room: a closed room lit only by a constant sky through a window. The frame's 16 sky
directions each cast a parallel shadow: before, every direction that passed the window drew
one hard, window-shaped patch on the floor and walls, and the frame mean moved 15% with the
seed. Now each direction's visibility is its mean over the cone of directions it stands for
(`sky_cone.wgsl`, biases stated there) and 64 directions are drawn (docs/bench/
sky-openings.md).

glass_room: a ceiling panel over a glass slab; the floor under the slab is lit only through
the glass (caustic transport: `ispm`'s photons traced through it on the CPU; the shadow maps
keep glass opaque, so the direct light does not count it twice; `direct`, direct light only,
is dark there as `path` at max_depth 1 is).
"""

import json
from pathlib import Path

import numpy as np
import pytest

import gi

DIR = Path(__file__).parent / "scenes" / "openings"
SEEDS = (1, 2, 3, 4)
PART = {"direct": "direct", "ispm": "full"}


def reference(name: str, part: str) -> np.ndarray:
    meta = json.loads((DIR / f"{name}-{part}.json").read_text())
    assert meta["spp"] >= 2048
    assert max(np.array(meta["stderr"]) / np.array(meta["mean"])) < 0.002
    return gi.read_image(DIR / f"{name}-{part}.exr")[..., :3]


def blocks(x: np.ndarray, k: int = 3) -> np.ndarray:
    h, w = x.shape[0] // k * k, x.shape[1] // k * k
    return x[:h, :w].reshape(h // k, k, w // k, k, *x.shape[2:]).mean((1, 3))


def floor_blocks(result) -> np.ndarray:
    """The 3x3 blocks wholly on the floor (y = 0)."""
    floor = (result.position[..., 1] < 0.02) & (result.depth > 0)
    return blocks(floor.astype(float)) > 0.99


def patch_error(img: np.ndarray, ref: np.ndarray, mask: np.ndarray) -> float:
    """Σ|a − b| / Σ b of the 3x3-block luminance over `mask` (blocks average the noise out
    and keep a hard patch, which sits where the reference has none)."""
    a, b = blocks(img.mean(-1)), blocks(ref.mean(-1))
    return float(np.abs(a - b)[mask].sum() / b[mask].sum())


@pytest.fixture(scope="module")
def window():
    return gi.load_scene(DIR / "window_room.json")


@pytest.fixture(scope="module")
def window_frames(window):
    return {m: {s: gi.render(window, m, seed=s) for s in SEEDS} for m in PART}


@pytest.mark.parametrize("method", sorted(PART))
def test_window_room_frame_means_match_path(method, window_frames):
    ref = reference("window_room", PART[method])
    means = np.array([window_frames[method][s].radiance[..., :3].mean() for s in SEEDS])
    ratio = means / ref.mean()
    print(method, ratio)
    assert np.all(np.abs(ratio - 1.0) < 0.05), ratio
    # The direct light's own spread (for `ispm` its `direct` AOV; the whole frame's is
    # `test_window_room_frame_spread`).
    frames = window_frames[method]
    direct = np.array([np.asarray(frames[s].aov("direct"))[..., :3].mean() for s in SEEDS])
    assert (direct.max() - direct.min()) / direct.mean() < 0.02, direct


@pytest.mark.parametrize("method", sorted(PART))
def test_window_room_frame_spread(method, window_frames):
    """One frame's image mean within 2% over seeds 1-4 (issue 44's must-show). For `ispm`
    the spread was its indirect light's: the sky's photons through the window (~3k of 200k
    stored; 4.0% over seeds 1-4, 6.8% over 1-8). Now a quarter as many photons again are
    aimed at the opening a pilot found, around every ray it marked (photon/sky_guide.rs,
    ~60k stored): 1.8% over 1-4 (the pilot's seed as committed; 1.0-1.7% at three others)
    and 2.4-3.1% over 1-8, mostly the direct light's own spread; the indirect AOV's 1.9-4.4%
    (22% with no aimed photon). With session 14's 512 kernels the indirect AOV spread
    3.2-6.8% and a quarter as many aimed photons failed this at three pilots of four
    (docs/bench/sky-openings.md)."""
    means = np.array([window_frames[method][s].radiance[..., :3].mean() for s in SEEDS])
    print(method, means)
    assert (means.max() - means.min()) / means.mean() < 0.02, means


# Measured (seeds 1-4): before (5d5b5fe, 16 directions) direct 1.05-1.87, ispm above 0.25
# (both asserts fail there; with 64 hard-shadowed directions direct 0.64-0.74, ispm
# 0.22-0.28); after (64 directions with their cones) direct 0.30-0.43, ispm 0.14-0.19; with
# the cones of half the directions a pixel (sky_cone.wgsl `SKY_CONE_SHARE`) direct 0.31-0.45,
# ispm 0.15-0.20; with the cones shared over 2x2 quads and ispm's sky photons aimed at the
# window as well (photon/sky_guide.rs) direct 0.33-0.45, ispm 0.12-0.16.
PATCH_BOUND = {"direct": 0.5, "ispm": 0.25}


@pytest.mark.parametrize("method", sorted(PART))
def test_window_room_floor_has_no_hard_patches(method, window_frames):
    ref = reference("window_room", PART[method])
    errors = []
    for s in SEEDS:
        r = window_frames[method][s]
        mask = floor_blocks(r)
        assert mask.sum() > 100
        errors.append(patch_error(r.radiance[..., :3], ref, mask))
    print(method, errors)
    assert max(errors) < PATCH_BOUND[method], errors


@pytest.fixture(scope="module")
def glass():
    return gi.load_scene(DIR / "glass_room.json")


def under_glass(result) -> np.ndarray:
    """The floor under the middle of the glass slab (x 0.3 ± 0.5, z −0.3 ± 0.5): lit by the
    panel only through the glass."""
    p = result.position
    return (
        (result.depth > 0)
        & (p[..., 1] < 0.02)
        & (np.abs(p[..., 0] - 0.3) < 0.5)
        & (np.abs(p[..., 2] + 0.3) < 0.5)
    )


@pytest.mark.parametrize("method", sorted(PART))
def test_glass_room_frame_means_match_path(method, glass):
    ref = reference("glass_room", PART[method])
    frames = [gi.render(glass, method, seed=s) for s in SEEDS[:2]]
    means = np.array([f.radiance[..., :3].mean() for f in frames])
    ratio = means / ref.mean()
    region = under_glass(frames[0])
    assert region.sum() > 100
    below = frames[0].radiance[..., :3][region].mean() / max(ref[region].mean(), 1e-6)
    print(method, ratio, "under the glass", below, ref[region].mean())
    assert np.all(np.abs(ratio - 1.0) < 0.05), ratio
    assert (means.max() - means.min()) / means.mean() < 0.02, means
    if method == "ispm":
        # Light through the glass is there (caustic photons), not a black shadow, and not
        # twice (the shadow maps keep the glass opaque to the direct light).
        assert abs(below - 1.0) < 0.08, below
    else:
        # Direct light only: nothing reaches the floor under the slab directly.
        assert ref[region].mean() < 1e-3
        assert frames[0].radiance[..., :3][region].mean() < 1e-3


def relmse(x: np.ndarray, ref: np.ndarray) -> float:
    return float(np.mean((x - ref) ** 2 / (ref**2 + 1e-2)))


@pytest.mark.parametrize("method", sorted(PART))
def test_window_room_progressive_converges_to_path(method, window):
    """Progressive passes draw new sky directions each (one tap each, no cone: unbiased
    sums), so their running mean converges to `path`: the error at pass 32 well under the
    pass-4 one (a mean that stopped converging keeps it)."""
    ref = reference("window_room", PART[method])
    extra = {"subsample": 1} if method == "ispm" else {}
    r = gi.Renderer(window, method, progressive=True, spp=1, **extra)
    errors = {}
    for n in range(1, 33):
        frame = r.render()
        if n in (4, 32):
            errors[n] = relmse(frame.radiance[..., :3], ref)
    print(method, errors)
    assert errors[32] < 0.5 * errors[4], errors
