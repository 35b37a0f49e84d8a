"""Progressive mode (issue 11): passes of probabilistic progressive photon mapping whose
running mean converges to the `path` reference."""

import os
import select
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

import gi

SIZE = (24, 24)


@pytest.fixture(scope="module")
def cornell_reference():
    # 4096 spp at 24x24 (≈2 s): its own relMSE against a second seed is about 4e-4 (measured),
    # an order of magnitude below the pass-64 errors the test compares.
    return gi.render(gi.load_scene("cornell"), "path", spp=4096, size=SIZE, seed=77).radiance


def relmse(x, ref):
    return float(np.mean((x - ref) ** 2 / (ref**2 + 1e-2)))


@pytest.mark.parametrize("method", ["gather", "ispm"])
def test_error_falls_between_pass_4_and_64(method, cornell_reference):
    # ispm at full resolution (subsample 1), as README advises for progressive rendering:
    # the bilateral upsampling of subsample 2 is a bias no pass removes (there pass 64 stays
    # at ~0.0075, 0.6x pass 4).
    extra = {"subsample": 1} if method == "ispm" else {}
    r = gi.Renderer(
        gi.load_scene("cornell"),
        method,
        size=SIZE,
        photons=20_000,
        spp=1,
        progressive=True,
        **extra,
    )
    errors = {}
    for n in range(1, 65):
        frame = r.render()
        assert frame.stats.passes == n == r.passes
        if n in (4, 64):
            errors[n] = relmse(frame.radiance, cornell_reference)
    print(method, errors)
    # Measured: gather 0.0158 -> 0.0018 (8.7x lower), ispm 0.0070 -> 0.0012 (5.8x). Sixteen
    # times the passes with radii shrinking to 16^-0.15 = 0.66x: variance alone falls ~7x.
    # Requiring half the pass-4 error leaves room for seed-to-seed noise (about ±20% at pass
    # 4), while a mode that averaged nothing keeps the pass-4 error.
    assert errors[64] < 0.5 * errors[4]


def test_mean_of_passes_and_reset_on_change():
    scene = gi.load_scene("cornell")
    settings = dict(size=(16, 16), photons=5_000, spp=1)
    r = gi.Renderer(scene, "gather", progressive=True, **settings)
    a = r.render().radiance
    b = r.render().radiance
    assert r.passes == 2 and not np.array_equal(a, b)
    # The first pass is the ordinary frame of the same seed.
    plain = gi.Renderer(scene, "gather", **settings).render().radiance
    np.testing.assert_array_equal(a, plain)
    # Pass 2 alone is (2·mean − pass 1): the mean is that of two distinct estimates.
    second = 2.0 * b - a
    assert np.abs(second - a).mean() > 1e-4
    r.update(lights={0: {"intensity": [2, 2, 2]}})
    assert r.passes == 0
    c = r.render()
    assert c.stats.passes == 1
    r.resize(8, 8)
    assert r.passes == 0 and r.render().radiance.shape == (8, 8, 3)


def test_render_progressive_counts_time_and_callbacks():
    r = gi.Renderer(
        gi.load_scene("cornell"), "gather", size=(8, 8), photons=2_000, spp=1, progressive=True
    )
    assert r.render_progressive(passes=5).stats.passes == 5
    seen = []
    out = r.render_progressive(passes=100, on_pass=lambda f: seen.append(f) or len(seen) < 3)
    assert out.stats.passes == 8 and len(seen) == 3
    out = r.render_progressive(seconds=0.2)
    assert out.stats.passes > 8
    # A callback that cancels mid-run returns the passes done so far.
    calls = []

    def progress(stage, fraction):
        calls.append(stage)
        return len(calls) < 40

    before = r.passes
    out = r.render_progressive(passes=10_000, progress=progress)
    assert before < out.stats.passes < 10_000 and set(calls) == {"passes"}


def test_bad_progressive_settings():
    scene = gi.load_scene("cornell")
    with pytest.raises(gi.SettingError, match="progressive"):
        gi.Renderer(scene, "photon", progressive=True)
    with pytest.raises(gi.SettingError, match="temporal_frames"):
        gi.Renderer(scene, "ispm", progressive=True, temporal_frames=4)
    with pytest.raises(gi.SettingError, match="progressive_alpha"):
        gi.Renderer(scene, "gather", progressive=True, progressive_alpha=1.0)
    plain = gi.Renderer(scene, "gather", size=(8, 8))
    with pytest.raises(gi.SettingError, match="progressive"):
        plain.render_progressive(passes=2)
    r = gi.Renderer(scene, "gather", size=(8, 8), progressive=True)
    for bad in [dict(), dict(passes=0), dict(seconds=-1.0), dict(seconds=float("nan"))]:
        with pytest.raises(gi.SettingError):
            r.render_progressive(**bad)


def run_cli(*args):
    return subprocess.run(
        [sys.executable, "-m", "gi.cli", *args], capture_output=True, text=True, timeout=300
    )


def test_cli_progressive_passes_and_errors(tmp_path):
    out = tmp_path / "p.exr"
    common = ["render", "caustic-ring", "--method", "gather", "--size", "16x16"]
    p = run_cli(*common, "-o", str(out), "--photons", "3000", "--progressive", "--passes", "3")
    assert p.returncode == 0, p.stderr
    assert "3 passes" in p.stderr
    assert gi.read_image(out).shape == (16, 16, 3)
    p = run_cli(*common, "-o", str(tmp_path / "q.exr"), "--progressive")
    assert p.returncode == 2 and "--time" in p.stderr
    p = run_cli(*common, "-o", str(tmp_path / "r.exr"), "--photons", "3000", "--passes", "3")
    assert p.returncode == 0 and "3 passes" in p.stderr  # --passes implies --progressive
    p = run_cli(*common, "-o", str(tmp_path / "q.exr"), "--progressive", "--time", "0")
    assert p.returncode == 2
    assert not (tmp_path / "q.exr").exists()


CLI_WITH_MARKER = """
import sys

import gi  # noqa: F401


class Marker:
    def __init__(self):
        self.seen = False

    def __call__(self, stage, fraction):
        if not self.seen and fraction > 0:
            self.seen = True
            print("RENDERING", file=sys.stderr, flush=True)
        return True

    def close(self):
        pass


sys.modules["gi.render"].ProgressBar = Marker
from gi.cli import main

sys.exit(main(sys.argv[1:]))
"""


def test_cli_ctrl_c_writes_the_passes_so_far(tmp_path):
    out = tmp_path / "x.exr"
    cmd = [sys.executable, "-c", CLI_WITH_MARKER, "render", "cornell", "-o", str(out)]
    cmd += ["--method", "gather", "--size", "16x16", "--photons", "5000", "--spp", "1"]
    cmd += ["--progressive", "--passes", "100000000"]
    with subprocess.Popen(cmd, stderr=subprocess.PIPE, stdout=subprocess.DEVNULL) as proc:
        assert proc.stderr is not None
        fd = proc.stderr.fileno()
        seen = b""
        deadline = time.monotonic() + 120
        while b"RENDERING" not in seen:
            ready, _, _ = select.select([fd], [], [], max(deadline - time.monotonic(), 0.0))
            assert ready, seen[-500:]
            chunk = os.read(fd, 4096)
            assert chunk, seen[-500:]
            seen += chunk
        time.sleep(0.5)
        assert proc.poll() is None
        proc.send_signal(signal.SIGINT)
        rc = proc.wait(timeout=30)
        rest = proc.stderr.read().decode(errors="replace")
    assert rc == 0, rest
    assert "interrupted" in rest and "Traceback" not in rest
    img = gi.read_image(out)
    assert img.shape == (16, 16, 3) and np.isfinite(img).all() and img.mean() > 0


# Per-pass settings of progressive `ispm` in docs/bench/progressive.md.
ISPM_PASS = dict(photons=20_000, spp=1, subsample=1, kernel_scale=0.5, progressive=True)


def crease_pixels(position, normal):
    """Pixels next to a crease or a depth step: a neighbour off the pixel's tangent plane
    by more than a tenth of their distance."""
    edge = np.zeros(position.shape[:2], bool)
    for axis in (0, 1):
        n = position.shape[axis]
        a = [slice(None), slice(None)]
        b = [slice(None), slice(None)]
        a[axis], b[axis] = slice(0, n - 1), slice(1, n)
        a, b = tuple(a), tuple(b)
        d = position[b] - position[a]
        off = np.maximum(
            np.abs(np.sum(d * normal[a], axis=-1)), np.abs(np.sum(d * normal[b], axis=-1))
        )
        jump = off > 0.1 * np.linalg.norm(d, axis=-1)
        edge[a] |= jump
        edge[b] |= jump
    return edge


def test_progressive_ispm_has_no_dark_creases():
    # The floor that progressive `ispm` had on cornell (docs/bench/progressive.md): the
    # photon-side boundary compensation left the indirect light too dark on the pixels
    # along creases, by an amount that shrinking kernels narrow but do not lower. Measured
    # here (64x64, 64 passes; mean signed error of the 717 lit pixels next to a crease
    # against `path`): −5.4% before (the indirect part alone −8.5%), −0.15% with the
    # query-side normalisation of progressive mode. The reference (1024 spp) adds about
    # ±0.3% of noise to that mean, the progressive mean at 64 passes about ±0.5% (two
    # seeds at 32x32 differed by 0.9%): 3% is far from both.
    scene = gi.load_scene("cornell")
    size = (64, 64)
    ref = gi.render(scene, "path", spp=1024, size=size, seed=77).radiance.mean(axis=-1)
    r = gi.Renderer(scene, "ispm", size=size, adapter="cpu", **ISPM_PASS)
    first = r.render(aovs=True)
    for _ in range(63):
        frame = r.render()
    assert frame.stats.passes == 64
    crease = crease_pixels(first.position, first.normal) & (ref > 0.05 * ref.mean())
    rel = (frame.radiance.mean(axis=-1) - ref) / ref
    bias = float(rel[crease].mean())
    print("crease pixels", crease.sum(), "bias", bias, "elsewhere", rel[~crease].mean())
    assert crease.sum() > 300
    assert abs(bias) < 0.03


def test_progressive_ispm_direct_light_converges():
    # Progressive `ispm` ray traces the direct light per pass instead of rasterizing it with
    # shadow maps (resolution, PCF, normal offset: a bias no pass removes). Its `direct`
    # image averaged over passes must converge to `path` at max_depth 1 like a Monte Carlo
    # mean, error ∝ 1/passes: measured on mirror-shadow 48x48 (the wall's shadow edge),
    # relMSE 9.4e-5 at 16 passes and 5.2e-6 at 256 (0.056×; 1/16 expected); with the
    # shadow-mapped direct light 2.2e-4 and 6.1e-5 (0.28×: the floor). The reference's own
    # error (16384 spp, ~0.8e-6 against a second seed's half of 1.6e-6) is a sixth of the
    # pass-256 error. The bound 0.15 sits 2.7× above the new and 1.9× below the old ratio.
    scene = gi.load_scene("mirror-shadow")
    size = (48, 48)
    ref = gi.render(scene, "path", spp=16384, size=size, seed=5, max_depth=1).radiance
    r = gi.Renderer(scene, "ispm", size=size, adapter="cpu", **ISPM_PASS)
    total = np.zeros_like(ref, dtype=np.float64)
    errors = {}
    for n in range(1, 257):
        total += r.render(extras=True).extra["direct"]
        if n in (16, 256):
            errors[n] = relmse(total / n, ref)
    print(errors)
    assert errors[256] < 0.15 * errors[16]
