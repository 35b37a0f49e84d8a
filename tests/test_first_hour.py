"""A newcomer's first hour (issue 46): the bugs a new user met, each through the entry point
the user used (the `gi` command or the Python API)."""

from __future__ import annotations

import pickle
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import gi
from gi.viewer import messages


def run(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "gi.cli", *args],
        capture_output=True,
        text=True,
        cwd=cwd,
        timeout=300,
    )


def python(code: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)


# -- 6. bugs ----------------------------------------------------------------------------------


def test_a_layered_exr_reads_as_its_beauty_and_saves_to_png(tmp_path):
    exr = tmp_path / "frame.exr"
    p = run(
        *["render", "cornell", "-o", str(exr), "--method", "path", "--spp", "1"],
        *["--size", "16x12", "--aov", "albedo", "--aov", "normal", "-q"],
    )
    assert p.returncode == 0, p.stderr
    assert len(gi.read_channels(exr)) == 9  # R G B, albedo.RGB, N.XYZ
    beauty = gi.read_image(exr)
    assert beauty.shape == (12, 16, 3)
    channels = gi.read_channels(exr)
    np.testing.assert_array_equal(beauty, np.stack([channels[c] for c in "RGB"], axis=2))
    albedo = gi.read_image(exr, layer="albedo")
    np.testing.assert_array_equal(
        albedo, np.stack([channels[f"albedo.{c}"] for c in "RGB"], axis=2)
    )
    gi.save_image(tmp_path / "x.png", gi.read_image(exr))  # failed: 9 channels for a PNG
    assert gi.read_image(tmp_path / "x.png").shape == (12, 16, 3)
    with pytest.raises(gi.SettingError, match="no layer 'specular'.*'N', 'albedo'"):
        gi.read_image(exr, layer="specular")


def test_the_viewer_names_the_photon_range_of_the_option_table():
    photons = next(row for row in gi.options_table() if row["name"] == "photons")
    with pytest.raises(messages.MessageError) as e:
        messages.parse('{"type": "settings", "settings": {"photons": -5}}', gi.methods())
    assert e.value.field == "settings.photons"
    assert photons["range"] in str(e.value) and "9223372036854775808" not in str(e.value)


def test_an_output_on_proc_gives_the_real_reason():
    # gi runs on Linux only (pyproject's classifiers), where /proc always exists.
    assert Path("/proc/self").exists()
    p = run("render", "cornell", "-o", "/proc/x.png", "--spp", "1")
    assert p.returncode == 2
    # root: procfs answers "no such file" for a directory that exists; others: permission.
    assert "makes no new files" in p.stderr or "permission denied" in p.stderr, p.stderr
    assert "No such file or directory" not in p.stderr


def test_exposure_with_only_float_outputs_warns(tmp_path):
    base = ["render", "cornell", "--method", "path", "--spp", "1", "--size", "8x8", "-q"]
    p = run(*base, "-o", str(tmp_path / "a.exr"), "--exposure", "2")
    assert p.returncode == 0, p.stderr
    assert "gi: warning: --exposure changes only 8-bit outputs" in p.stderr
    p = run(*base, "-o", str(tmp_path / "b.exr"), "--tonemap", "filmic", "--exposure", "1")
    assert "--exposure and --tonemap change only 8-bit outputs" in p.stderr
    p = run(*base, "-o", str(tmp_path / "c.exr"), "-o", str(tmp_path / "c.png"), "--exposure", "2")
    assert p.returncode == 0 and p.stderr == ""


def test_frames_past_the_end_of_the_animation_warn(tmp_path):
    # cornell-anim lasts 4 s: at 30 fps frame 120 is its end, 121 and later repeat it.
    base = ["render", "cornell-anim", "--method", "direct", "--spp", "1", "--size", "8x8", "-q"]
    p = run(*base, "-o", str(tmp_path / "f_%04d.exr"), "--frames", "118:123")
    assert p.returncode == 0, p.stderr
    assert "2 of the 5 frames (121..122) are past the end of cornell-anim's 4 s" in p.stderr
    p = run(*base, "-o", str(tmp_path / "g_%04d.exr"), "--frames", "0:2")
    assert p.returncode == 0 and p.stderr == ""
    p = run(
        "render",
        "cornell",
        "--method",
        "direct",
        "--spp",
        "1",
        "--size",
        "8x8",
        "-q",
        "-o",
        str(tmp_path / "s_%02d.exr"),
        "--frames",
        "0:2",
    )
    assert p.returncode == 0 and "cornell has no animation" in p.stderr


def test_exceptions_present_as_gi_classes():
    p = python("import gi; gi.load_scene('no-such-scene')")
    assert "\ngi.SceneError: no-such-scene" in p.stderr and "_gi." not in p.stderr, p.stderr
    p = python("import gi; gi.save_image('x.bmpx', [[1.0]])")
    assert "\ngi.SettingError: unsupported image format" in p.stderr, p.stderr
    assert "_checks" not in p.stderr
    r = gi.render("cornell", "direct", size=(4, 4))
    try:
        r.aov("nope")
    except KeyError as e:
        assert f"{type(e).__module__}.{type(e).__qualname__}" == "gi.SettingError"
    for cls in (gi.SceneError, gi.OutputError, gi.RenderWarning, gi.OutOfMemoryError):
        assert cls.__module__ == "gi"
    err = pickle.loads(pickle.dumps(gi.SceneError("x")))
    assert type(err) is gi.SceneError


def test_footprints_count_hits_not_photons():
    p = run("footprints", "cornell", "--photons", "2000")
    assert p.returncode == 0, p.stderr
    head, columns, *rows = p.stdout.splitlines()
    assert "2000 photons emitted" in head and "hits stored" in head
    assert columns.split()[:2] == ["kind", "hits"]
    # One photon stores a hit at every diffuse bounce: more hits than photons is no error.
    assert sum(int(r.split()[1]) for r in rows) > 2000


def test_describe_gives_back_the_angle_given():
    r = gi.Renderer("cornell", "direct", size=(8, 8))
    r.update(objects={6: {"rotate": [0, 295, 0]}})
    assert r.describe("object", 6)["transform"]["rotate"] == [0, 295, 0]
    r.update(objects={6: {"translate": np.array([0.1, 0.5, 0.0])}})
    t = r.describe("object", 6)["transform"]
    assert t["rotate"] == [0, 295, 0] and t["translate"] == [0.1, 0.5, 0.0]
    assert t["scale"] == 1.0
    # The same rotation as -65°: the picture and the matrix agree.
    m295 = np.array(r.describe("object", 6)["matrix"])
    r.update(objects={6: {"rotate": [0, -65, 0]}})
    assert r.describe("object", 6)["transform"]["rotate"] == [0, -65, 0]
    np.testing.assert_allclose(np.array(r.describe("object", 6)["matrix"]), m295, atol=1e-6)
    # A matrix update reads back as the matrix taken apart.
    r.update(objects={6: {"matrix": np.eye(4)}})
    assert r.describe("object", 6)["transform"] == {
        "translate": [0.0, 0.0, 0.0],
        "rotate": [0.0, 0.0, 0.0],
        "scale": 1.0,
    }


# -- 4. one default method ----------------------------------------------------------------------


def test_one_default_method_everywhere_and_said_so():
    import inspect

    from gi.render import render_animation

    assert gi.DEFAULT_METHOD in gi.methods()
    for entry in (gi.render, gi.Renderer.__init__, gi.view, render_animation):
        method = inspect.signature(entry).parameters["method"]
        assert method.default == gi.DEFAULT_METHOD, entry
    from gi.batch import plan

    job = {"scene": "cornell", "frames": [0, 1], "output": "out/{index}.exr"}
    assert [f.method for f in plan(job)] == [gi.DEFAULT_METHOD]
    for command in ("render", "view"):
        p = run(command, "--help")
        assert f"(default {gi.DEFAULT_METHOD}, as in gi.render" in " ".join(p.stdout.split())
    p = run("methods")
    defaults = [line.split()[0] for line in p.stdout.splitlines() if "(the default)" in line]
    assert defaults == [gi.DEFAULT_METHOD]
    # And what renders without one is that method.
    assert gi.render("cornell", size=(8, 8)).stats.method == gi.DEFAULT_METHOD


# -- 2. budgets users set are kept (and issue 42 item 4) -----------------------------------


def test_progressive_time_is_kept_within_a_pass():
    """``seconds`` cancels the pass under way when the time is up. Passes of ``path`` at
    16 spp (about a second each here) and a budget of 1.2 passes: checked only between
    passes, the run took 2 passes; checked within one, 1.2 passes and the gap between two
    progress reports (~0.1 s, 2% of a pass). The bound, 1.6 passes, leaves 0.4 of a pass
    for that gap and for passes of unequal length on a loaded machine: a behaviour check,
    not a speed benchmark."""
    r = gi.Renderer("cornell", "path", size=(128, 128), spp=16, progressive=True)
    start = time.monotonic()
    r.render_progressive(passes=1)
    one_pass = time.monotonic() - start
    start = time.monotonic()
    result = r.render_progressive(seconds=1.2 * one_pass)
    wall = time.monotonic() - start
    assert wall < 1.6 * one_pass, (wall, one_pass)
    # The first pass of a run completes, the one cut short is dropped: 2 passes in all.
    assert result.stats.passes == 2 and np.isfinite(result.radiance).all()


def test_cli_time_implies_progressive_and_small_passes(tmp_path):
    out = tmp_path / "g.exr"
    p = run(
        "render", "cornell", "--method", "gather", "--size", "32x32", "--time", "1", "-o", str(out)
    )
    assert p.returncode == 0, p.stderr
    assert "progressive:" in p.stderr and "passes of spp 1, photons 30000" in p.stderr
    assert gi.read_image(out).shape == (32, 32, 3)
    p = run(
        "render",
        "cornell",
        "--method",
        "ispm",
        "--size",
        "16x16",
        "--passes",
        "2",
        "--photons",
        "2000",
        "-o",
        str(tmp_path / "i.exr"),
    )
    assert p.returncode == 0 and "2 passes of spp 1, photons 2000, subsample 1" in p.stderr
    p = run(
        "render",
        "cornell",
        "--size",
        "16x16",
        "--passes",
        "2",
        "--no-progressive",
        "-o",
        str(tmp_path / "n.exr"),
    )
    assert p.returncode == 2 and "--time and --passes render progressively" in p.stderr


# -- 7. CLI ergonomics ------------------------------------------------------------------------


def test_an_argument_error_is_one_line_and_a_hint():
    p = run("render", "cornell", "-o", "x.png", "--spp", "many")
    assert p.returncode == 2
    assert p.stderr.splitlines() == [
        "gi render: error: argument --spp: invalid int value: 'many'",
        "(`gi render --help` lists the options)",
    ]
    p = run("render")
    assert p.returncode == 2 and len(p.stderr.splitlines()) == 2 and "required" in p.stderr


def test_help_speaks_the_command_lines_words():
    for command in ("render", "view"):
        p = run(command, "--help")
        text = " ".join(p.stdout.split())
        assert p.returncode == 0 and "None" not in text and "True" not in text, command
        assert "(auto: one per camera sample)" in text
        # argparse breaks lines at hyphens: compared without white space.
        assert "(--no-edge-supersampling:everypixel" in "".join(text.split())
        # --progressive lists the methods that take it: not photon, which refuses it.
        progressive = text[text.index("--progressive, --no-progressive") :]
        methods = progressive[: progressive.index("]")].split("default off;")[1]
        assert "photon" not in methods and "gather" in methods


def test_frame_numbers_either_way(tmp_path):
    base = ["render", "cornell-anim", "--method", "direct", "--spp", "1", "--size", "8x8", "-q"]
    p = run(
        *base,
        "--frames",
        "0:2",
        "-o",
        str(tmp_path / "a_{frame:03d}.exr"),
        "-o",
        str(tmp_path / "b_%02d.png"),
    )
    assert p.returncode == 0, p.stderr
    names = sorted(f.name for f in tmp_path.iterdir())
    assert names == ["a_000.exr", "a_001.exr", "b_00.png", "b_01.png"]
    p = run(*base, "--frames", "0:2", "-o", str(tmp_path / "c_{frame}_%d.exr"))
    assert p.returncode == 2 and "more than one frame number" in p.stderr
    from gi.batch import plan

    job = {"scene": "cornell", "method": "direct", "frames": [3, 5], "output": "f/%04d.exr"}
    assert [Path(f.outputs[0]).name for f in plan(job, tmp_path)] == ["0003.exr", "0004.exr"]


def test_stage_times_only_when_verbose_and_in_pipeline_order(tmp_path):
    from gi.cli import PIPELINE

    args = ["render", "cornell", "--size", "16x16", "--photons", "2000", "--method", "ispm"]
    p = run(*args, "-o", str(tmp_path / "a.png"))
    assert p.returncode == 0, p.stderr
    assert len(p.stderr.splitlines()) == 1 and "shadow maps" not in p.stderr
    p = run(*args, "-o", str(tmp_path / "b.png"), "-v")
    stages = [line.split("  ")[1].strip() for line in p.stderr.splitlines() if line[:2] == "  "]
    # ispm reports its GPU stages (shadow maps, gbuffer, ...) after its CPU ones.
    assert {"shadow maps", "cpu trace", "composite"} <= set(stages), p.stderr
    assert [PIPELINE.index(s) for s in stages] == sorted(PIPELINE.index(s) for s in stages)


# -- 1. the viewer in every method ------------------------------------------------------------


def test_the_viewer_engine_uses_quick_frames_and_says_so():
    from gi.presets import INTERACTIVE
    from gi.viewer.engine import Engine

    frames = []
    engine = Engine(
        gi.load_scene("cornell"),
        "gather",
        {"size": (64, 48)},
        on_frame=frames.append,
        on_event=lambda client, message: None,
    )
    state = engine.state()
    assert state["options"]["photons"]["default"] == INTERACTIVE["gather"].options["photons"]
    engine.start()
    try:
        frame = engine.wait_frame(120)
        assert frame is not None
        assert frame.meta["doing"] == "moving: 32×24, 1 spp, 10000 photons a frame"
        assert frame.pixels.shape == (24, 32, 3)
    finally:
        engine.stop()
