"""Animation: keyframed tracks in the scene format, `Renderer.render_animation`, the CLI's
image sequences and videos, and the README's animation examples, run as a user would (tiny
sizes and photon counts)."""

import io
import json
import os
import pty
import re
import subprocess
import sys
from pathlib import Path

import imageio_ffmpeg
import numpy as np
import pytest

import gi
from gi import cli
from gi.animation import FrameProgressBar
from gi.video import VideoWriter

SIZE = (32, 24)
# ISPM with few photons: fast, and still every stage of the method.
ISPM = {"size": SIZE, "photons": 2000}
README = Path(__file__).resolve().parent.parent / "README.md"
SCENE_FORMAT = README.parent / "docs" / "scene-format.md"


def run(*args, cwd=None, **kw):
    return subprocess.run(
        [sys.executable, "-m", "gi.cli", *args],
        capture_output=True,
        text=True,
        cwd=cwd,
        timeout=300,
        **kw,
    )


def test_builtin_tracks_evaluate():
    scene = gi.load_scene("cornell-anim")
    assert scene.animation_duration == 4.0
    assert gi.load_scene("cornell").animation_duration is None
    assert gi.animation_updates(gi.load_scene("cornell"), 1.0) == {}
    u = gi.animation_updates(scene, 0.25)
    assert set(u) == {"lights", "objects"}
    # Halfway between the light's keys at 0 s and 0.5 s; f64 interpolation of the keys.
    np.testing.assert_allclose(
        u["lights"][0]["position"], [(0.45 + 0.3182) / 2, 1.6, 0.3182 / 2], atol=1e-12
    )
    assert u["lights"][0]["intensity"] == [3.0, 3.0, 3.0], "fields not animated are kept"
    box = u["objects"]["tall box"]
    np.testing.assert_allclose(box["translate"], [-0.3875, 0.6, -0.35], atol=1e-12)
    assert box["rotate"] == [0.0, 20.0, 0.0] and box["scale"] == 1.0
    # The end keys hold outside the animation.
    assert gi.animation_updates(scene, 10.0) == gi.animation_updates(scene, 4.0)
    with pytest.raises(gi.SettingError, match="time"):
        gi.animation_updates(scene, float("nan"))


def test_render_animation_poses_every_frame_like_fresh_renderers():
    """Each frame of a sequence equals a new renderer posed by `animation_updates` at the
    frame's time. Bitwise: method `direct` is deterministic and the persistent renderer must
    not keep anything of the earlier poses."""
    scene = gi.load_scene("cornell-anim")
    frames = dict(gi.render_animation(scene, "direct", [0, 5, 15], fps=10, size=SIZE))
    assert list(frames) == [0, 5, 15]
    for n, frame in frames.items():
        fresh = gi.Renderer(scene, "direct", size=SIZE)
        fresh.update(**gi.animation_updates(scene, n / 10))
        assert np.array_equal(frame.radiance, fresh.render().radiance), n
    # The light and the box moved: the frames differ.
    assert np.abs(frames[0].radiance - frames[15].radiance).max() > 0.05
    assert np.abs(frames[5].radiance - frames[15].radiance).max() > 0.05


def test_mesh_object_animated_in_a_scene_file(cornell_desc, write_scene, tmp_path):
    """A user's scene file: a PLY mesh (written by trimesh) named and animated; the ball is
    where the track puts it (the position AOV's nearest surface at the image centre)."""
    import trimesh

    trimesh.creation.icosphere(subdivisions=2, radius=0.25).export(tmp_path / "ball.ply")
    cornell_desc["objects"].append(
        {"name": "ball", "shape": {"type": "mesh", "file": "ball.ply"}, "material": "red"}
    )
    cornell_desc["animation"] = {
        "tracks": [
            {
                "target": "object",
                "name": "ball",
                "keys": [
                    {"time": 0, "value": {"translate": [0, 1, 0.5]}},
                    {"time": 1, "value": {"translate": [0, 1.4, 0.5]}},
                ],
            }
        ]
    }
    scene = gi.load_scene(write_scene(cornell_desc))
    assert scene.animation_duration == 1.0
    r = gi.Renderer(scene, "direct", size=SIZE)
    heights = {}
    for n, frame in r.render_animation([0, 2], fps=2, aovs=True):
        column = frame.position[:, SIZE[0] // 2]
        albedo = frame.albedo[:, SIZE[0] // 2]
        red = (albedo[:, 0] > 0.5) & (albedo[:, 1] < 0.2)  # the ball, down the middle
        heights[n] = column[red, 1].mean()
    # The ball's visible centre height rose by the track's 0.4 m (within the ball's radius:
    # its visible points are the near cap, not the centre).
    assert 0.3 < heights[2] - heights[0] < 0.5, heights


def test_animation_errors_name_the_field(cornell_desc, write_scene):
    cornell_desc["objects"][-1]["name"] = "tall box"

    def load(animation):
        return gi.load_scene(write_scene({**cornell_desc, "animation": animation}))

    def key(t, v):
        return {"time": t, "value": v}

    cases = [
        (
            {"tracks": [{"target": "light", "index": 0, "keys": [key(1, {}), key(0, {})]}]},
            "animation.tracks[0].keys[0].value",
        ),
        (
            {
                "tracks": [
                    {
                        "target": "light",
                        "index": 0,
                        "keys": [
                            key(1, {"position": [0, 1, 0]}),
                            key(0.5, {"position": [0, 1, 1]}),
                        ],
                    }
                ]
            },
            "animation.tracks[0].keys[1].time",
        ),
        (
            {"tracks": [{"target": "object", "name": "teapot", "keys": [key(0, {"scale": 2})]}]},
            "animation.tracks[0].name",
        ),
        (
            {"tracks": [{"target": "object", "name": "tall box", "keys": [key(0, {"scale": 0})]}]},
            "animation.tracks[0].keys[0].value.scale",
        ),
        (
            {"tracks": [{"target": "camera", "keys": [key(0, {"fov": "wide"})]}]},
            "animation.tracks[0].keys[0].value.fov",
        ),
        ({"duration": 0, "tracks": []}, "animation.duration"),
    ]
    for animation, field in cases:
        with pytest.raises(gi.SceneError) as e:
            load(animation)
        assert e.value.field == field, (e.value, animation)


def test_scene_format_example_is_valid(cornell_desc, write_scene):
    """The `animation` example of docs/scene-format.md loads (on the Cornell box with the
    tall box named as in the example)."""
    text = SCENE_FORMAT.read_text()
    block = text[text.index("## animation") :].split("```json")[1].split("```")[0]
    cornell_desc["objects"][-1]["name"] = "tall box"
    cornell_desc.update(json.loads("{" + block + "}"))
    scene = gi.load_scene(write_scene(cornell_desc))
    assert scene.animation_duration == 4.0
    u = gi.animation_updates(scene, 3.5)
    assert set(u) == {"camera", "lights", "objects", "materials"}
    assert u["materials"]["red"]["diffuse"] == [0.1, 0.1, 0.6], "step: the key at 3 s holds"
    np.testing.assert_allclose(u["camera"]["fov"], 40 - 10 * 3.5 / 4, atol=1e-12)


def test_render_animation_checks_arguments_before_rendering():
    scene = gi.load_scene("cornell-anim")
    r = gi.Renderer(scene, "direct", size=SIZE)
    with pytest.raises(gi.SettingError, match="fps"):
        r.render_animation([0], fps=0)
    with pytest.raises(gi.SettingError, match="frames"):
        r.render_animation([0, -1])
    with pytest.raises(gi.SettingError, match="frames"):
        r.render_animation([])
    with pytest.raises(gi.SettingError, match="no animation"):
        gi.Renderer(gi.load_scene("cornell"), "direct", size=SIZE).render_animation()
    assert r.frame_index == 0, "nothing rendered"
    # The whole animation by default: round(4 s · 2 fps) frames.
    assert [n for n, _ in r.render_animation(fps=2)] == list(range(8))


def test_progress_over_the_sequence():
    scene = gi.load_scene("cornell-anim")
    r = gi.Renderer(scene, "direct", size=SIZE)
    seen = []
    for _ in r.render_animation(range(3), progress=lambda stage, f: seen.append((stage, f))):
        pass
    assert seen == [("frames", 0.0), ("frames", 1 / 3), ("frames", 2 / 3), ("frames", 1.0)]
    with pytest.raises(gi.RenderCancelled):
        for _ in r.render_animation(range(3), progress=lambda stage, f: f < 0.5):
            pass

    class Terminal(io.StringIO):
        def isatty(self):
            return True

    tty, log = Terminal(), io.StringIO()
    for stream in (tty, log):
        bar = FrameProgressBar(3, stream)
        for done in range(4):
            bar(done)
    assert "3/3" in tty.getvalue() and "100.0%" in tty.getvalue()
    assert log.getvalue() == "", "quiet when not a terminal"


def read_video(path):
    """(frames as (H, W, 3) uint8 arrays, (width, height)), decoded by the ffmpeg of
    imageio-ffmpeg (its `read_frames` leaves pipes open when ffmpeg finishes first)."""
    ffmpeg = imageio_ffmpeg.get_ffmpeg_exe()
    p = subprocess.run(
        [ffmpeg, "-i", str(path), "-f", "rawvideo", "-pix_fmt", "rgb24", "-"],
        capture_output=True,
        check=True,
        timeout=60,
    )
    w, h = map(int, re.search(r"Video: .*?, (\d+)x(\d+)[, ]", p.stderr.decode()).groups())
    return list(np.frombuffer(p.stdout, np.uint8).reshape(-1, h, w, 3)), (w, h)


def test_cli_sequence_and_video_match_the_python_api(tmp_path):
    p = run(
        "render",
        "cornell-anim",
        "--frames",
        "0:12:4",
        "--fps",
        "10",
        "--size",
        "32x24",
        "--photons",
        "2000",
        "-o",
        "out/frame_%04d.exr",
        "-o",
        "out/png/f_%02d.png",
        "-o",
        "out/anim.mp4",
        "--aov",
        "albedo",
        cwd=tmp_path,
    )
    assert p.returncode == 0, p.stderr
    # Not a terminal: no bar, one summary line.
    assert "frames [" not in p.stderr and "wrote 3 frames" in p.stderr, p.stderr
    out = tmp_path / "out"
    # Each frame is one EXR with the AOV as layers, like a still's.
    assert sorted(f.name for f in out.glob("*.exr")) == [f"frame_{n:04d}.exr" for n in (0, 4, 8)]
    assert sorted(gi.read_channels(out / "frame_0000.exr")) == sorted(
        ["R", "G", "B", "albedo.R", "albedo.G", "albedo.B"]
    )
    r = gi.Renderer(gi.load_scene("cornell-anim"), "ispm", **ISPM)
    expected = dict(r.render_animation(range(0, 12, 4), fps=10))
    for n, frame in expected.items():
        # Bitwise: the same renderer, settings and seeds; EXR stores float32 as it is.
        assert np.array_equal(gi.read_image(out / f"frame_{n:04d}.exr")[..., :3], frame.radiance), n
        png = np.round(gi.read_image(out / "png" / f"f_{n:02d}.png") * 255).astype(np.uint8)
        assert np.array_equal(png, gi.io.to_srgb8(frame.radiance)), n
    video, size = read_video(out / "anim.mp4")
    assert size == SIZE and len(video) == 3
    assert imageio_ffmpeg.count_frames_and_secs(str(out / "anim.mp4"))[0] == 3
    luma = np.array([0.299, 0.587, 0.114])  # BT.601, ffmpeg's RGB -> YUV for this size
    for frame, n in zip(video, (0, 4, 8), strict=True):
        srgb = gi.io.to_srgb8(expected[n].radiance).astype(float)
        # H.264 at CRF 10 in yuv420p: chroma is halved (a 32x24 frame's coloured wall edges
        # differ by up to ~50 levels per channel), luma is near lossless. Measured: mean
        # |luma error| 1.3-1.8 levels, channel means within 1.7 levels; asserted 3 and 3.
        assert np.abs(frame @ luma - srgb @ luma).mean() < 3, n
        assert np.abs(frame.mean(axis=(0, 1)) - srgb.mean(axis=(0, 1))).max() < 3, n
    assert not list(out.glob(".*")), "no partial files left"


def test_cli_progress_bar_on_a_terminal(tmp_path):
    controller, terminal = pty.openpty()
    p = subprocess.Popen(
        [sys.executable, "-m", "gi.cli", "render", "cornell-anim", "--frames", "0:3"]
        + ["--size", "16x12", "--method", "direct", "-o", "f_%d.png"],
        stderr=terminal,
        stdout=subprocess.DEVNULL,
        cwd=tmp_path,
    )
    os.close(terminal)
    chunks = []
    while True:
        try:
            data = os.read(controller, 4096)
        except OSError:  # EIO: the child closed the terminal
            break
        if not data:
            break
        chunks.append(data)
    os.close(controller)
    assert p.wait(timeout=300) == 0
    err = b"".join(chunks).decode()
    assert "frames [" in err and "3/3" in err and "wrote 3 frames" in err, err


def test_cli_checks_outputs_and_frames_before_rendering(tmp_path):
    cases = [
        (["-o", "frame.png", "--frames", "0:2"], "frame number in its name"),
        (["-o", "f_%s.png"], "%d or %04d"),
        (["-o", "f_%d_%d.png"], "more than one"),
        (["-o", "v_%d.mp4"], "video takes no frame number"),
        (["-o", "v.avi"], "unsupported"),
        (["-o", "f_%d.png", "--frames", "3:1"], "START < END"),
        (["-o", "f_%d.png", "--fps", "-1"], "--fps"),
    ]
    for args, message in cases:
        p = run("render", "cornell-anim", *args, cwd=tmp_path)
        assert p.returncode == 2 and message in p.stderr, (args, p.stderr)
    p = run("render", "cornell", "-o", "v.mp4", cwd=tmp_path)
    assert p.returncode == 2 and "no animation" in p.stderr, p.stderr
    assert list(tmp_path.iterdir()) == [], "nothing written"


def test_video_writer_leaves_no_half_file(tmp_path):
    frame = np.zeros((25, 33, 3), np.uint8)
    w = VideoWriter(tmp_path / "a.mp4", fps=24)
    w.write(frame)
    with pytest.raises(ValueError, match="differs"):
        w.write(np.zeros((24, 32, 3), np.uint8))
    w.abort()
    assert list(tmp_path.iterdir()) == []
    # Odd sizes are padded to even ones (yuv420p).
    w = VideoWriter(tmp_path / "b.mp4", fps=24)
    for _ in range(2):
        w.write(frame)
    w.close()
    video, size = read_video(tmp_path / "b.mp4")
    assert size == (34, 26) and len(video) == 2
    assert [f.name for f in tmp_path.iterdir()] == ["b.mp4"]


def test_video_without_its_encoder_package_is_a_typed_error(tmp_path, monkeypatch):
    # An install that lacks imageio-ffmpeg (the GPU check's image had none): an OutputError
    # naming the package, from the API and the CLI, and no file left.
    monkeypatch.setitem(sys.modules, "imageio_ffmpeg", None)  # import raises ImportError
    w = VideoWriter(tmp_path / "a.mp4", fps=24)
    with pytest.raises(gi.OutputError, match="pip install imageio-ffmpeg"):
        w.write(np.zeros((8, 8, 3), np.uint8))
    w.abort()
    args = cli._parser().parse_args(
        ["render", "cornell-anim", "-o", str(tmp_path / "v.mp4"), "--size", "8x8"]
        + ["--spp", "1", "--photons", "300", "--frames", "0:2", "-q"]
    )
    with pytest.raises(gi.OutputError, match="imageio-ffmpeg"):
        cli.run(args)
    assert list(tmp_path.iterdir()) == []


def readme_section() -> str:
    text = README.read_text()
    return text[text.index("## Animation") :].split("\n## ")[0]


def test_readme_cli_commands(tmp_path):
    """The README's commands, run as written with a smaller size, fewer frames and photons
    appended (argparse keeps the last value of a repeated option)."""
    sh = readme_section().split("```sh")[1].split("```")[0]
    commands = [line.split("#")[0].split() for line in sh.splitlines() if line.startswith("gi ")]
    assert len(commands) == 2
    for cmd in commands:
        assert cmd[:3] == ["gi", "render", "cornell-anim"]
        p = run(
            *cmd[1:], "--frames", "0:2", "--size", "32x24", "--photons", "2000", "-q", cwd=tmp_path
        )
        assert p.returncode == 0, (cmd, p.stderr)
    out = tmp_path / "out"
    for name in ("frame_0000.exr", "frame_0001.exr", "f_000.png", "f_001.png"):
        assert (out / name).is_file(), name
    video, size = read_video(out / "cornell-anim.mp4")
    assert size == SIZE and len(video) == 2


def test_readme_python_example(tmp_path, monkeypatch):
    """The README's Python example, run as written with a smaller size and fewer frames."""
    code = readme_section().split("```python")[1].split("```")[0]
    smaller = {
        "size=(320, 240), photons=20_000": "size=(32, 24), photons=2_000",
        "range(0, 120)": "range(0, 2)",
    }
    for old, new in smaller.items():
        assert old in code, old
        code = code.replace(old, new)
    monkeypatch.chdir(tmp_path)
    printed = io.StringIO()
    monkeypatch.setattr(sys, "stdout", printed)
    exec(compile(code, str(README), "exec"), {})
    assert sorted(f.name for f in (tmp_path / "out").iterdir()) == [
        "frame_0000.png",
        "frame_0001.png",
    ]
    assert re.search(r"'tall box'", printed.getvalue())


def test_soak_script_records_rss(tmp_path):
    """scripts/probe/soak_rss.py (its committed 1000-frame result is docs/bench/rss.md), run short:
    it writes its table and exits 0 inside the band."""
    script = README.parent / "scripts" / "probe" / "soak_rss.py"
    out = tmp_path / "rss.md"
    p = subprocess.run(
        [sys.executable, str(script), "--frames", "12", "--warmup", "4", "--size", "16x12"]
        + ["--photons", "500", "--tolerance", "0.5", "--out", str(out)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert p.returncode == 0, p.stderr
    text = out.read_text()
    assert "| 11 |" in text and "within" in text, text
