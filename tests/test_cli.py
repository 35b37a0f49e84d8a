"""The `gi` command line, run as a user would."""

import subprocess
import sys

import numpy as np

import gi


def run(*args, cwd=None):
    return subprocess.run(
        [sys.executable, "-m", "gi.cli", *args],
        capture_output=True,
        text=True,
        cwd=cwd,
        timeout=300,
    )


def test_render_png_and_exr_with_aovs(tmp_path):
    out = tmp_path / "c.exr"
    p = run("render", "cornell", "-o", str(out), "--spp", "2", "--size", "32x24", "--aov", "albedo")
    assert p.returncode == 0, p.stderr
    img = gi.read_image(out)  # the beauty; the layers by name
    assert img.shape == (24, 32, 3) and img.mean() > 0
    assert gi.read_image(out, layer="albedo").shape == (24, 32, 3)
    # The AOV is a layer of the same EXR, not a second file.
    assert sorted(gi.read_channels(out)) == ["B", "G", "R", "albedo.B", "albedo.G", "albedo.R"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.exr"]
    p = run(
        "render", "cornell", "-o", str(tmp_path / "c.png"), "--spp", "1", "--size", "16x16", "-q"
    )
    assert p.returncode == 0 and p.stderr == ""
    assert gi.read_image(tmp_path / "c.png").shape == (16, 16, 3)


def test_png_aovs_tonemap_and_all(tmp_path):
    out = tmp_path / "d.png"
    args = ["render", "cornell", "-o", str(out), "--spp", "1", "--size", "16x16", "-q"]
    p = run(*args, "--method", "path", "--aov", "all", "--tonemap", "filmic", "--exposure", "1")
    assert p.returncode == 0, p.stderr
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == sorted(
        ["d.png"] + [f"d.{a}.png" for a in ("albedo", "normal", "position", "depth", "caustics")]
    )
    assert gi.read_image(tmp_path / "d.depth.png").shape == (16, 16, 1)


def test_bad_outputs_fail_before_rendering(tmp_path):
    # Each of these used to render first (seconds to hours) and fail when writing.
    base = ["render", "cornell", "--spp", "100000", "--size", "512x512"]
    out = tmp_path / "out"
    (tmp_path / "dir.exr").mkdir()
    cases = [
        (["-o", str(out / "x.bmpx")], "unsupported output format"),
        (["-o", str(out / "x.exr"), "--aov", "indirect", "--method", "path"], "no AOV"),
        (["-o", str(tmp_path / "dir.exr")], "is a directory"),
        (["-o", str(out / "a.png"), "-o", str(out / "a.png")], "written twice"),
        (["-o", str(out / "x.png"), "--method", "nope"], "unknown method"),
    ]
    for extra, message in cases:
        p = run(*base, *extra)
        assert p.returncode == 2 and message in p.stderr, (extra, p.stderr)
    p = run(*base, "-o", str(out / "x.png"), "--tonemap", "reinhard")
    assert p.returncode == 2 and "--tonemap" in p.stderr
    assert not out.exists()


def test_version():
    p = run("--version")
    assert p.returncode == 0 and p.stdout.strip() == f"gi {gi.__version__}"


def test_progress_bars_in_a_terminal_and_quiet_in_logs(tmp_path):
    import fcntl
    import os
    import pty
    import struct
    import termios

    args = ["render", "cornell", "-o", str(tmp_path / "c.png"), "--spp", "1", "--size", "16x16"]
    # Piped (a log file, CI): no progress frames at all, only the summary line.
    p = run(*args)
    assert p.returncode == 0 and "wrote" in p.stderr
    assert "\r" not in p.stderr and "%|" not in p.stderr, p.stderr
    # In a terminal: tqdm bars, one per stage, redrawn with carriage returns.
    leader, follower = pty.openpty()
    fcntl.ioctl(follower, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 80, 0, 0))
    proc = subprocess.Popen(
        [sys.executable, "-m", "gi.cli", *args], stdout=follower, stderr=follower
    )
    os.close(follower)
    chunks = []
    while True:
        try:
            data = os.read(leader, 65536)
        except OSError:  # EIO: the child closed the terminal
            break
        if not data:
            break
        chunks.append(data)
    os.close(leader)
    assert proc.wait(timeout=300) == 0
    text = b"".join(chunks).decode(errors="replace")
    assert "100.0%|" in text and "\r" in text and "cpu trace" in text, text


def test_scenes_lists_builtins():
    p = run("scenes")
    assert p.returncode == 0 and "cornell-glass" in p.stdout and "furnace" in p.stdout
    assert "ring-room" in p.stdout


def test_errors_exit_non_zero_with_a_message(tmp_path):
    p = run("render", str(tmp_path / "missing.json"), "-o", str(tmp_path / "x.png"))
    assert p.returncode == 2 and "gi: error:" in p.stderr and "Traceback" not in p.stderr
    p = run("render", "cornell", "-o", str(tmp_path / "x.png"), "--spp", "0")
    assert p.returncode == 2 and "spp" in p.stderr
    p = run("render", "cornell", "-o", str(tmp_path / "x.bmpx"), "--spp", "1", "--size", "4x4")
    assert p.returncode == 2 and "unsupported" in p.stderr
    p = run("render", "cornell", "-o", "x.png", "--size", "12")
    assert p.returncode == 2 and "WIDTHxHEIGHT" in p.stderr


def test_scene_file_with_relative_mesh(tmp_path):
    import trimesh

    (tmp_path / "meshes").mkdir()
    trimesh.creation.icosphere(subdivisions=2, radius=0.3).export(tmp_path / "meshes" / "ball.stl")
    desc = gi.builtin_json("cornell").replace(
        '"objects": [',
        '"objects": [{"shape": {"type": "mesh", "file": "meshes/ball.stl"}, '
        '"transform": {"translate": [0, 1, 0]}, "material": "red"},',
        1,
    )
    (tmp_path / "scene.json").write_text(desc)
    out = tmp_path / "o.exr"
    p = run(
        "render", "scene.json", "-o", str(out), "--spp", "1", "--size", "16x16", "-q", cwd=tmp_path
    )
    assert p.returncode == 0, p.stderr
    assert np.isfinite(gi.read_image(out)).all()


def test_info_prints_the_adapter():
    p = run("info", "--adapter", "cpu")
    assert p.returncode == 0 and "gi " in p.stdout and "backend" in p.stdout.lower(), p.stdout


def test_footprints_prints_a_table():
    p = run("footprints", "caustic-ring", "--photons", "20000")
    assert p.returncode == 0, p.stderr
    assert "caustic" in p.stdout and "direct" in p.stdout and "p50" in p.stdout


def test_volume_shape_option(tmp_path):
    out = tmp_path / "q.exr"
    args = ["render", "cornell", "-o", str(out), "--spp", "1", "--size", "16x16", "-q"]
    p = run(*args, "--photons", "5000", "--volume-shape", "quad")
    assert p.returncode == 0, p.stderr
    assert gi.read_image(out).mean() > 0
    p = run(*args, "--volume-shape", "sphere")
    assert p.returncode == 2 and "--volume-shape" in p.stderr


def test_estimator_option(tmp_path):
    out = tmp_path / "t.exr"
    args = ["render", "cornell", "-o", str(out), "--spp", "1", "--size", "16x16"]
    p = run(*args, "--photons", "5000", "--estimator", "tiled", "-v")
    assert p.returncode == 0, p.stderr
    assert "estimator tiled: chosen in the settings" in p.stderr
    assert gi.read_image(out).mean() > 0
    p = run(*args, "-q", "--estimator", "splat")
    assert p.returncode == 2 and "--estimator" in p.stderr


def test_first_bounce_option(tmp_path):
    out = tmp_path / "t.exr"
    args = ["render", "cornell", "-o", str(out), "--spp", "1", "--size", "16x16"]
    p = run(*args, "--photons", "5000", "--first-bounce", "raster", "--verbose")
    assert p.returncode == 0, p.stderr
    assert "first bounce raster: chosen in the settings" in p.stderr
    assert gi.read_image(out).mean() > 0
    p = run(*args, "-q", "--first-bounce", "rays")
    assert p.returncode == 2 and "--first-bounce" in p.stderr


def test_footprints_of_all_three_path_kinds():
    # ring-room: the mirror ring's caustic amid diffusely reflected light (the paper's Table 3).
    p = run("footprints", "ring-room", "--photons", "20000")
    assert p.returncode == 0, p.stderr
    kinds = {line.split()[0] for line in p.stdout.splitlines()[2:]}
    assert kinds == {"caustic", "diffuse", "direct"}, p.stdout
