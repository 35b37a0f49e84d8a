"""The GPU direct light on veach-mis (Bitterli's scene, `tests/scenes/third_party/veach-mis`:
four plates of increasing roughness lit by three sphere lights of equal power and very
different size, the smallest 0.05 wide with radiance 3039), against Mitsuba 3.9.1's direct
light (`reference-direct.exr`: `max_depth` 2, 4096 spp at 160×90,
`scripts/data/mitsuba_third_party.py --direct`; its mean's standard error 0.33%).

The spheres are tessellated (5120 triangles each) but found round (`scene/emitters/round.rs`):
each is a polygon group of one record, its unshadowed light summed in closed form per pixel
as the disc it shows the point (`round_lights.wgsl`: Lambert's vector irradiance of the
disc's 12-gon for the diffuse lobe; the glossy lobe by linearly transformed cosines, or by a
7-point quadrature of the plates' own Beckmann lobe where the disc is small against it:
`ltc_direct.wgsl`), shadowed by the ratio of the group's shadow-mapped points. Before (issue
44 item 1) their light was drawn per shading point from a light BVH: noisy highlights, FLIP
0.22-0.24; before that every pixel shared 16 points drawn for the whole frame: the lit part
of one frame's mean varied by ±17% with the seed and the highlights came and went.

Measured on the whole frame (its mean's spread over seeds, FLIP, the highlights) and on
its *lit* part: everything but the directly seen spheres (discs around their projections,
widened by 1.5 pixels). The directly seen spheres are the G-buffer's, not the light
selection's: the smallest is under a pixel at this size and no pixel-centre sample finds it
(`raster/edges.rs`: sub-pixel features are not found), so the whole frame lacked its 22% of
the reference's mean until emitters under a pixel were splatted by their cover
(`raster/subpixel.rs`; `test_frame_mean_matches_mitsuba`, `test_smallest_sphere_is_seen`).
"""

import json
import warnings
from pathlib import Path

import numpy as np
import pytest
from image_metrics import flip

import gi

SCENE = Path(__file__).parent / "scenes" / "third_party" / "veach-mis"
SIZE = (160, 90)
SEEDS = (1, 2, 3, 4)
# The sphere lights (centre, radius) and the camera of scene.xml: at (28.2792, 3.5, 0)
# looking down -x, its image x along -z, 35° across.
SPHERES = [((0.0, 6.5, -2.8), 1.0), ((0.0, 6.5, 0.0), 0.5), ((0.0, 6.5, 2.7), 0.05)]
EYE = np.array([28.2792, 3.5, 0.0])


def sphere_mask() -> np.ndarray:
    """Pixels within 1.5 pixels of a sphere light's projected disc."""
    w, h = SIZE
    t = np.tan(np.radians(17.5))
    yy, xx = np.mgrid[0:h, 0:w] + 0.5
    mask = np.zeros((h, w), bool)
    for centre, radius in SPHERES:
        d = np.array(centre) - EYE
        depth = -d[0]
        px = w / 2 - d[2] / depth / t * w / 2
        py = h / 2 - d[1] / depth / t * w / 2
        rp = radius / depth / t * w / 2
        mask |= (xx - px) ** 2 + (yy - py) ** 2 <= (rp + 1.5) ** 2
    return mask


def components(mask: np.ndarray) -> list[np.ndarray]:
    """The 4-connected components of `mask`, each as a mask."""
    seen = np.zeros_like(mask)
    out = []
    h, w = mask.shape
    for y0, x0 in zip(*np.nonzero(mask), strict=True):
        if seen[y0, x0]:
            continue
        comp = np.zeros_like(mask)
        stack = [(y0, x0)]
        seen[y0, x0] = True
        while stack:
            y, x = stack.pop()
            comp[y, x] = True
            for v, u in ((y + 1, x), (y - 1, x), (y, x + 1), (y, x - 1)):
                if 0 <= v < h and 0 <= u < w and mask[v, u] and not seen[v, u]:
                    seen[v, u] = True
                    stack.append((v, u))
        out.append(comp)
    return out


@pytest.fixture(scope="module")
def scene():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return gi.load_scene(SCENE / "scene.xml")


@pytest.fixture(scope="module")
def reference():
    meta = json.loads((SCENE / "reference-direct.json").read_text())
    assert meta["max_depth"] == 2 and meta["spp"] >= 4096 and meta["size"] == list(SIZE)
    assert max(np.array(meta["stderr"]) / np.array(meta["mean"])) < 0.005
    return gi.read_image(SCENE / "reference-direct.exr")[..., :3]


def render(scene, method: str, seed: int) -> np.ndarray:
    """One frame at the defaults; the only warning allowed is the GPU's uber stand-ins for
    the plates' Beckmann conductors (issue 42's work)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        img = gi.render(scene, method, size=SIZE, seed=seed).radiance
    for w in caught:
        assert issubclass(w.category, gi.RenderWarning) and "uber stand-ins" in str(w.message)
    return img


@pytest.fixture(scope="module")
def full_reference():
    return gi.read_image(SCENE / "reference.exr")[..., :3]


@pytest.fixture(scope="module")
def frames(scene):
    """One `direct` frame per seed (the defaults: 16 light samples a pixel)."""
    return {s: render(scene, "direct", s) for s in SEEDS}


@pytest.fixture(scope="module")
def ispm_frames(scene):
    """One `ispm` frame per seed (its defaults)."""
    return {s: render(scene, "ispm", s) for s in SEEDS}


def highlight_regions(reference: np.ndarray) -> list[np.ndarray]:
    """The reference's highlights on the plates: connected regions of the lit part brighter
    than 0.25, below the lights' row, of at least 4 pixels."""
    lit = ~sphere_mask()
    lum = reference.mean(axis=2)
    below = np.zeros_like(lit)
    below[30:] = True
    return [c for c in components((lum > 0.25) & lit & below) if c.sum() >= 4]


def test_mask_covers_the_directly_seen_spheres(reference):
    """The mask is where the spheres are: the reference's brightest pixel (the smallest
    sphere, radiance 3039) and every pixel of the lights' rows above the largest's
    radiance (7.6) in it, and it leaves out most of the image."""
    mask = sphere_mask()
    lum = reference.mean(axis=2)
    assert mask[np.unravel_index(np.argmax(lum), lum.shape)]
    assert mask[:30][lum[:30] > 7.0].all()
    assert mask.mean() < 0.1


@pytest.mark.parametrize("method", ["direct", "ispm"])
def test_frame_means_are_stable_across_seeds(method, frames, ispm_frames):
    """The whole frame's mean per channel within 2% across seeds 1-4 (a still view does not
    flicker with the draw). Was 0.71-0.87 of the reference (`direct`, 22%), then 1.2-1.8%;
    with the spheres' closed form 0.07% (`direct`) and 0.2% (`ispm`)."""
    imgs = frames if method == "direct" else ispm_frames
    means = np.array([imgs[s].mean(axis=(0, 1)) for s in SEEDS])
    print(method, "frame means per seed:", np.round(means, 4).tolist())
    spread = means.max(axis=0) / means.min(axis=0) - 1
    assert np.all(spread <= 0.02), spread


@pytest.mark.parametrize("method", ["direct", "ispm"])
def test_lit_mean_matches_mitsuba(method, frames, ispm_frames, reference, full_reference):
    """Per seed, the lit part's mean per channel within 5% of Mitsuba's (`direct` against
    the direct light, `ispm` against the full reference). Was 0.78-1.21 (`direct`), then
    0.96-1.03; now 1.007-1.012 (`direct`), 1.008-1.015 (`ispm`)."""
    imgs, ref_img = (frames, reference) if method == "direct" else (ispm_frames, full_reference)
    lit = ~sphere_mask()
    ref = ref_img[lit].mean(axis=0)
    ratios = np.array([imgs[s][lit].mean(axis=0) / ref for s in SEEDS])
    print(method, "lit mean / Mitsuba per seed:", np.round(ratios, 4).tolist())
    assert np.all(np.abs(ratios - 1) <= 0.05), ratios


def test_frame_mean_matches_mitsuba(frames, reference):
    """The whole frame's mean within 5% of Mitsuba's direct light. Was 0.77-0.79 (the
    smallest sphere under a pixel, seen by no pixel centre); with the sub-pixel emitters
    splatted by their cover (`raster/subpixel.rs`) 0.98-1.00 per channel and seed."""
    ratios = np.array([frames[s].mean(axis=(0, 1)) / reference.mean(axis=(0, 1)) for s in SEEDS])
    print("direct frame mean / Mitsuba per seed:", np.round(ratios, 4).tolist())
    assert np.all(np.abs(ratios - 1) <= 0.05), ratios


def test_smallest_sphere_is_seen(frames, reference):
    """The smallest sphere's own pixels (its disc widened by 1.5 pixels, no other light
    there) hold its light: their sum within 5% of the reference's per seed (was 0.001-0.003:
    only the wall behind it, main at 5d5b5fe seeds 1-2; now 0.98)."""
    w, h = SIZE
    centre, radius = SPHERES[2]
    t = np.tan(np.radians(17.5))
    d = np.array(centre) - EYE
    px = w / 2 - d[2] / -d[0] / t * w / 2
    py = h / 2 - d[1] / -d[0] / t * w / 2
    yy, xx = np.mgrid[0:h, 0:w] + 0.5
    near = (xx - px) ** 2 + (yy - py) ** 2 <= (radius / -d[0] / t * w / 2 + 1.5) ** 2
    ref = reference[near].sum(axis=0)
    ratios = np.array([frames[s][near].sum(axis=0) / ref for s in SEEDS])
    print("smallest sphere's pixels / Mitsuba per seed:", np.round(ratios, 4).tolist())
    assert np.all(np.abs(ratios - 1) <= 0.05), ratios


@pytest.mark.parametrize("method", ["direct", "ispm"])
def test_frame_shows_every_highlight(method, frames, ispm_frames, reference, full_reference):
    """Every highlight of the reference on the plates (`highlight_regions`: 9 in the
    direct light, one per light and plate but the roughest plate's; 11 with indirect light)
    holds 80-125% of the reference's light in a frame of each seed. Was 0.28-2.8 (16 points
    a frame), then 0.71-1.26 (the light tree's samples, a widened lobe); now, with the
    spheres' closed form, 0.86-1.17 (`direct`) and 0.86-1.20 (`ispm`), the same in every
    seed; with the Beckmann LTC table (session 14) 0.89-1.21 and 0.89-1.24: the highest is
    the smallest sphere's on the smoothest plate (α 0.01: its disc, ρ ≈ α, at the edge of
    the quadrature's range, blended with LTC), the lowest the medium and large spheres' on
    the second plate (α 0.05: 0.86-0.87 with the GGX fit for the Beckmann lobe)."""
    imgs, ref_img = (frames, reference) if method == "direct" else (ispm_frames, full_reference)
    regions = highlight_regions(ref_img)
    assert len(regions) >= 9, len(regions)
    lum = ref_img.mean(axis=2)
    for s in SEEDS:
        img = imgs[s].mean(axis=2)
        shares = [img[c].sum() / lum[c].sum() for c in regions]
        print(f"{method} seed {s}: highlight shares", np.round(shares, 2).tolist())
        assert min(shares) >= 0.8 and max(shares) <= 1.25, (s, shares)


@pytest.mark.parametrize("method,bound", [("direct", 0.13), ("ispm", 0.16)])
def test_frame_flip(method, bound, frames, ispm_frames, reference, full_reference):
    """FLIP of a frame against Mitsuba (the issue asks 0.20). Was 0.32-0.47 (`direct`),
    0.29-0.43 (`ispm`), then 0.22-0.24 and 0.20-0.21 (the light tree; 0.155-0.165 for
    `direct` on main at e0ed5ee, seeds 1-2); with the spheres' closed form 0.092-0.101 and
    0.120-0.129; with the Beckmann table and more sides for large discs 0.088-0.097 and
    0.117-0.127. The bounds leave ~0.03 above the measured values and fail main's."""
    imgs, ref_img = (frames, reference) if method == "direct" else (ispm_frames, full_reference)
    values = [flip(ref_img, imgs[s]) for s in SEEDS]
    print(method, "FLIP per seed:", np.round(values, 3).tolist())
    assert max(values) <= bound, values
