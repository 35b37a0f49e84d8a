"""Caustic kernels from the local photon density, and photon focusing (issue 11)."""

import numpy as np
import pytest

import gi


def dots(x, window=9, factor=4.0):
    """Share of pixels brighter than `factor` times the median of the `window`² pixels
    around them (isolated bright dots), ignoring pixels under 1% of the image mean (the
    measure of scripts/bench/bench_caustics.py)."""
    y = x.mean(axis=2)
    pad = window // 2
    windows = np.lib.stride_tricks.sliding_window_view(
        np.pad(y, pad, mode="edge"), (window, window)
    )
    median = np.median(windows, axis=(2, 3))
    return float(np.mean((y > factor * median) & (y > 0.01 * y.mean())))


def fireflies(x, ref, window=9, factor=4.0):
    """The issue's firefly measure (as in scripts/bench/bench_caustics.py): share of pixels whose
    error against the reference is over `factor` times the median error of the `window`²
    pixels around them, errors under 1% of the reference mean counting as none."""
    e = np.abs(x - ref).mean(axis=2)
    pad = window // 2
    windows = np.lib.stride_tricks.sliding_window_view(
        np.pad(e, pad, mode="edge"), (window, window)
    )
    median = np.median(windows, axis=(2, 3))
    return float(np.mean((e > factor * median) & (e > 0.01 * ref.mean())))


def test_caustic_kernels_and_focusing_lower_the_firefly_share_against_path():
    # cornell-glass: light the glass and mirror spheres scatter around the room lands as
    # isolated caustic photons; with the base kernel each is a dot. "Before" is ISPM without
    # the density bound and without photon focusing; "after" its defaults (the bound, and
    # 0.25 of each light's photons aimed at the spheres). Reference: path with 1024 spp and
    # 16M light paths (~7 s here; its caustics are light-traced).
    #
    # At 200k photons the two no longer differ since caustic photons' kernels are at least a
    # pixel wide (issue 29, in both variants): seeds 0-5 against this reference, firefly
    # share 0.052 before and 0.051 after, relMSE 0.01088 and 0.01081. The earlier test at
    # 200k photons (0.038 against 0.036 with a 256-spp reference) measured the reference's
    # own noise and failed once path's Russian roulette changed that noise. The bound and
    # focusing matter where caustic photons are few: at 20k photons (seeds 0-2), against
    # references of seeds 99, 5 and 11 and one of 256 spp, the firefly share is 0.044-0.047
    # before and 0.033-0.034 after (0.73-0.78x), relMSE 0.0185-0.0197 before and
    # 0.0163-0.0176 after (about -11%). Bounds: after under 0.85x before and under 0.04, and a
    # lower relMSE.
    scene = gi.load_scene("cornell-glass")
    ref = gi.render(
        scene, "path", size=(48, 48), spp=1024, light_paths=16_000_000, seed=99
    ).radiance
    # The passes pinned to those measured (on lavapipe, "auto" picks the CPU estimator and
    # the traced first bounce; a GPU picks tiled and raster, whose photon sets differ):
    # the comparison is of the bound and focusing, not of the adapter's choices.
    pinned = dict(estimator="cpu", first_bounce="traced")
    variants = {
        "before": dict(caustic_density_bound=False, photon_focus=0.0, **pinned),
        "after": pinned,
    }
    images = {
        name: [
            gi.render(scene, "ispm", size=(48, 48), photons=20_000, seed=s, **kw).radiance
            for s in (0, 1, 2)
        ]
        for name, kw in variants.items()
    }
    shares = {name: np.mean([fireflies(x, ref) for x in xs]) for name, xs in images.items()}
    rel_mse = {
        name: np.mean([np.mean((x - ref) ** 2 / (ref * ref + 0.01)) for x in xs])
        for name, xs in images.items()
    }
    print(shares, rel_mse)
    assert shares["after"] < 0.04
    assert shares["after"] < 0.85 * shares["before"]
    assert rel_mse["after"] < rel_mse["before"]


def test_density_bound_removes_isolated_caustic_dots():
    # mirror-shadow: a mirror sphere spreads a dim caustic over a floor in shadow. Without
    # the bound ISPM splats each caustic photon with the base radius: isolated dots.
    scene = gi.load_scene("mirror-shadow")
    shares = {}
    for bound in (False, True):
        # Without the bound also without focusing (the bench's "before"): focusing's extra
        # caustic photons, a pixel wide each, fill the shadowed floor in as well.
        kw = {} if bound else dict(caustic_density_bound=False, photon_focus=0.0)
        img = gi.render(scene, "ispm", size=(48, 48), photons=100_000, **kw).radiance
        shares[bound] = dots(img)
    print(shares)
    # Measured at 48x48 (docs/bench/caustics.md): 0.128 without, 0.032 with the bound, the
    # converged reference's own share 0.036 (sharp features count too). The bound must
    # bring the share under 0.08 and at least halve it. This ran at 32x32 (0.140 -> 0.066)
    # until caustic kernels became at least a pixel wide (issue 29): there every caustic
    # kernel is now a pixel wide with or without the bound (both 0.064), and at 48x48 with
    # focusing the unbounded share is 0.040: pixel-wide kernels over focusing's photons
    # remove the dots too. Without focusing the dots remain: measured 0.144 -> 0.035 here.
    assert shares[True] < 0.08
    assert shares[True] < 0.5 * shares[False]


@pytest.fixture(scope="module")
def glass_path_means():
    scene = gi.load_scene("cornell-glass")
    return [
        float(gi.render(scene, "path", spp=256, size=(24, 24), seed=s).radiance.mean())
        for s in (11, 12, 13)
    ]


def test_focused_gather_keeps_the_image_mean(glass_path_means):
    scene = gi.load_scene("cornell-glass")
    means = {}
    for focus in (0.0, 0.5):
        means[focus] = [
            float(
                gi.render(
                    scene,
                    "gather",
                    size=(24, 24),
                    photons=50_000,
                    spp=2,
                    seed=s,
                    photon_focus=focus,
                ).radiance.mean()
            )
            for s in (1, 2, 3)
        ]
    ref = np.mean(glass_path_means)
    ref_se = np.std(glass_path_means, ddof=1) / np.sqrt(3)
    print(ref, ref_se, means)
    for focus, m in means.items():
        se = np.std(m, ddof=1) / np.sqrt(3)
        # Within 3.5 combined standard errors of the path mean, plus 1% for the kernels'
        # bias (gather's mean was within 0.1% of the reference on cornell-glass at 48x48 in
        # docs/bench/caustics.md). Measured: path 0.5431 ± 0.0004; gather 0.538 ± 0.008
        # unfocused, 0.537 ± 0.006 focused (the spread is the diffuse photons'; the caustic
        # power itself is checked far tighter in crates/core/tests/focus.rs).
        tol = 3.5 * np.hypot(se, ref_se) + 0.01 * ref
        assert abs(np.mean(m) - ref) < tol, (focus, np.mean(m), ref, tol)


def test_caustic_ring_excess_is_the_mirror_seen_caustic():
    # caustic-ring's ispm mean was +8-10% over `path` (docs/bench/caustics.md). Nearly all of
    # it is in the ~20% of pixels that show the ring's mirror walls: they reflect the floor
    # inside the ring, half of whose light is the cardioid caustic, and `path` cannot render
    # a point light's caustic seen in a mirror (light -> mirror -> floor -> mirror -> camera:
    # camera paths never hit the point light, light paths cannot connect to the camera
    # through the mirror) while photon mapping does. Off those pixels the means must agree.
    # Reference: path with 256 spp and 16M light paths (~5 s here).
    scene = gi.load_scene("caustic-ring")
    ref = gi.render(scene, "path", size=(48, 48), spp=256, light_paths=16_000_000, seed=99)
    ref = ref.radiance
    ispm = [gi.render(scene, "ispm", size=(48, 48), photons=200_000, seed=s) for s in (0, 1)]
    # Pixels showing something in a mirror: ispm's `specular` image is not black there.
    mirror = np.any([r.extra["specular"].max(axis=-1) > 0 for r in ispm], axis=0)
    gather = [
        gi.render(scene, "gather", size=(48, 48), photons=200_000, spp=4, seed=s).radiance
        for s in (0, 1)
    ]
    ratios = {}
    for name, imgs in (("ispm", [r.radiance for r in ispm]), ("gather", gather)):
        m = np.mean(imgs, axis=0)
        ratios[name] = (
            m[~mirror].mean() / ref[~mirror].mean(),
            m[mirror].mean() / ref[mirror].mean(),
        )
    print(mirror.mean(), ratios)
    # Measured: mirror pixels 21% of the image; off them ispm 1.030, gather 0.998; on them
    # ispm 1.75, gather 1.71 (the floor they reflect is 53% caustic light: up to 2.15x).
    # Bounds: ispm within 5% off the mirrors (its half-resolution splat's upsampling adds
    # ~2.5 points here, ~0.5 its kernels; at subsample 1 it is +0.7%), gather within 2.5%;
    # both over 1.3x path on the mirror pixels (the light path cannot carry).
    assert abs(ratios["ispm"][0] - 1) < 0.05
    assert abs(ratios["gather"][0] - 1) < 0.025
    assert ratios["ispm"][1] > 1.3 and ratios["gather"][1] > 1.3
