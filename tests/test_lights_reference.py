"""gi against Mitsuba 3 on the reference scenes of issue 28 (`docs/scenes/`): Mitsuba's own
Cornell box (an area light), a sun and a sky, a room lit by emissive surfaces only.

The references are Mitsuba 3 path-traced images, 64×64, committed beside the scenes
(`scripts/data/lights_reference.py mitsuba` renders them; CI never runs Mitsuba), one per
`max_depth` that gi's methods trace by default (64; 3, `bidir`'s old two-bounce default;
1 for `direct`, which renders direct light), Mitsuba's `max_depth` one more (it counts
path segments, gi scattering events). Their means are known to better than 0.1%
(`docs/scenes/references.json`: the standard error of each mean from 16 independent
batches). Every method renders every scene without a `gi.RenderWarning` (a kind of light
left out) or a refusal, and must match the image mean of the reference of its `max_depth`:
`path` within 1%, the others within 3%; `docs/bench/lights.md` has every
method's ratio and FLIP at converged settings. Where `FLIP_BOUND` names a scene and method,
the frame's FLIP against the reference is bounded too.

The settings keep the file to about a minute on two cores. `path`'s image mean has a
standard error (measured over six seeds) of 0.36% in the Cornell box at 256 samples per
pixel (next-event estimation of its small area light; 0.53% when only the paths' own rays
found it), hence 512 there (about 0.26%: the 1% bound is 3.9 standard errors), and of
0.09% and below 0.01% in the room and under the sun and sky at 256. The 3% of the
other methods is the issue's bound for their bias at 200k photons or 16 samples. `photon`
took the sun's direct light from the photons, whose k-nearest-neighbour estimate darkened
the edges of the sun-lit boxes (under the sun and sky 200k photons left the image 3.7%
dark, hence 600k there); it now traces a shadow ray to the lights (frame/photon.rs):
ratios at 200k photons 0.988 (cornell-box), 0.986 (sun and sky), 0.995 (emissive room).

`bidir`'s indirect light of area lights, the sun and the sky comes from VPLs at the first
hits of 64 photons a frame (`frame/bidir/emitted.rs`): one frame's image mean varies by
several percent (sun and sky, where 26 of 64 photons hit the plate and a few the houses:
the indirect light of single frames was 20–85% of the reference's), so its image is the
mean of 16 progressive passes (new VPLs and bundles each). Measured over seeds 11–13:
0.987–1.008 (Cornell box), 0.986–1.004 (sun and sky), 0.976–0.990 (emissive room), since
its light of two and more bounces is two strategies combined by MIS (issue 29; before,
with the bundles' connections clamped at 10% of the scene's diagonal: 0.976–0.990,
0.981–1.001, 0.963–0.975); hence 3%, as the other methods (2% for the point-lit Cornell
boxes in `crates/core/tests/bidir.rs::any_depth_matches_path_tracer`, where many frames
average the noise).
"""

import json
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
from image_metrics import flip

import gi

ROOT = Path(__file__).resolve().parent.parent
SCENES = ROOT / "docs" / "scenes"
NAMES = ["cornell-box", "sun-sky", "emissive-room"]
SIZE = 64
SETTINGS = {
    "path": {"spp": 256},
    "photon": {"photons": 200_000, "spp": 16},
    "gather": {"photons": 200_000, "spp": 16},
    "direct": {"spp": 16},
    "ispm": {"photons": 200_000, "spp": 16},
    "bidir": {"spp": 16, "progressive": True},
}
PASSES = {"bidir": 16}  # progressive passes averaged (see the module doc)
TOLERANCE = {"path": 0.01}  # the others: 0.03
MORE = {  # see the module doc
    ("cornell-box", "path"): {"spp": 512},
}


# One frame's mean HDR-FLIP against the reference, where a bound guards a measured
# improvement: `direct`'s one frame of the room lit by emitting objects, since the GPU direct
# light takes its emitting objects in polygon groups with points stratified over them
# (`docs/bench/lights-gpu.md`). Measured at seeds 11-13: 0.237 / 0.296 / 0.281; before, with
# the room's emitters summed from 16 points drawn by power alone: 0.434 / 0.412 / 0.412.
FLIP_BOUND = {("emissive-room", "direct"): 0.35}

DEPTHS = (64, 3, 1)  # the references' gi max_depth


def reference_file(name: str, depth: int) -> Path:
    return SCENES / name / f"reference-depth{depth}.exr"


def test_references_are_small_and_converged():
    meta = json.loads((SCENES / "references.json").read_text())
    for name in NAMES:
        for depth in DEPTHS:
            key = f"{name}-depth{depth}"
            img = gi.read_image(reference_file(name, depth))[..., :3]
            assert img.shape == (SIZE, SIZE, 3) and np.isfinite(img).all()
            assert reference_file(name, depth).stat().st_size < 80_000
            assert img.mean() == pytest.approx(meta[key]["mean"], rel=1e-5)
            # The reference's own noise is well below the tolerances checked against it.
            assert meta[key]["stderr"] < 0.001 * meta[key]["mean"], key
            assert meta[key]["max_depth"] == depth + 1


@pytest.mark.parametrize("method", gi.methods())
@pytest.mark.parametrize("name", NAMES)
def test_method_matches_mitsuba(name, method):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the scene files load without an AssetWarning
        scene = gi.load_scene(SCENES / name / f"{name}.xml")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        # Every method takes every light scene (a refusal, gi.SettingError, fails the test).
        settings = {**SETTINGS[method], **MORE.get((name, method), {})}
        r = gi.Renderer(scene, method, size=(SIZE, SIZE), seed=11, **settings)
    warned = [str(w.message) for w in caught if issubclass(w.category, gi.RenderWarning)]
    depth = int(r.options.get("max_depth", 1))  # `direct` renders direct light
    if depth not in DEPTHS:
        pytest.fail(f"no reference for max_depth {depth} (scripts/data/lights_reference.py)")
    passes = PASSES.get(method)
    img = (r.render_progressive(passes=passes) if passes else r.render()).radiance
    ref = gi.read_image(reference_file(name, depth))[..., :3]
    assert np.isfinite(img).all()
    ratio = float(img.mean() / ref.mean())
    # Every method renders every kind of light (the last gap, `bidir`'s VPLs of area lights
    # and suns, is closed): a warning fails.
    assert not warned, (method, name, warned)
    assert abs(ratio - 1) <= TOLERANCE.get(method, 0.03), (
        f"{method} on {name}: image mean {img.mean():.5f}, Mitsuba's {ref.mean():.5f} at "
        f"max_depth {depth} (ratio {ratio:.4f})"
    )
    bound = FLIP_BOUND.get((name, method))
    if bound is not None:
        error = flip(ref, img)
        assert error < bound, f"{method} on {name}: FLIP {error:.3f} (bound {bound})"


def test_readme_first_example(tmp_path):
    """The README's first commands (Mitsuba's Cornell box from its XML, with `path` and the
    default method), run as written at a smaller size and fewer samples."""
    text = (ROOT / "README.md").read_text()
    sh = text[text.index("## Use") :].split("```sh")[1].split("```")[0]
    commands = [line.split("#")[0].split() for line in sh.splitlines() if line.startswith("gi ")]
    assert len(commands) == 2
    outputs = []
    for cmd in commands:
        assert cmd[:3] == ["gi", "render", "docs/scenes/cornell-box/cornell-box.xml"]
        cmd[2] = str(ROOT / cmd[2])
        outputs.append(tmp_path / cmd[cmd.index("-o") + 1])
        p = subprocess.run(
            [sys.executable, "-m", "gi.cli", *cmd[1:], "--size", "16x16", "--spp", "4", "-q"],
            cwd=tmp_path, capture_output=True, text=True, timeout=300,
        )  # fmt: skip
        assert p.returncode == 0, (cmd, p.stderr)
    for out in outputs:
        assert gi.read_image(out).shape == (16, 16, 3)
    # The path tracer sees the area light: the image is lit.
    assert gi.read_image(outputs[0]).mean() > 0.01
