"""What a new user tripped on (issue 32): sequence outputs, `.hdr` AOVs, Mitsuba `lookat`,
update checks, messages and help. The CLI cases run the real `gi` command."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import OpenImageIO as oiio  # noqa: N813 (the package's own usual alias)
import pytest
import trimesh

import gi
from gi import display, io

ROOT = Path(__file__).resolve().parent.parent
SMALL = {"size": (16, 16), "spp": 1, "photons": 2000, "max_depth": 4}


def small(method: str) -> dict:
    """SMALL's options that ``method`` takes."""
    return gi.method_options(method, **SMALL)


def run(*args: str, cwd: Path | None = None, timeout: float = 300) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "gi.cli", *args],
        capture_output=True,
        text=True,
        cwd=cwd,
        timeout=timeout,
    )


@pytest.fixture(scope="module")
def cornell() -> gi.Scene:
    return gi.load_scene("cornell")


# -- 1. sequences take the still-frame output path ------------------------------------------


def test_sequence_frames_are_written_like_stills(tmp_path):
    p = run(
        *("render", "cornell-anim", "--frames", "0:2", "--size", "16x12", "--photons", "2000"),
        *("-o", "f_%03d.exr", "-o", "p_%03d.png", "--aov", "all", "-q"),
        *("--tonemap", "filmic", "--exposure", "1"),
        cwd=tmp_path,
    )
    assert p.returncode == 0, p.stderr
    # EXR: one file per frame, the AOVs as layers (depth as `Z`), with the gi:* header.
    assert sorted(f.name for f in tmp_path.glob("*.exr")) == ["f_000.exr", "f_001.exr"]
    channels = gi.read_channels(tmp_path / "f_001.exr")
    assert {"R", "albedo.R", "N.X", "P.X", "Z", "direct.R", "photons.R"} <= set(channels)
    spec = oiio.ImageInput.open(str(tmp_path / "f_001.exr")).spec()
    assert spec.getattribute("gi:method") == "ispm" and spec.getattribute("gi:passes") == 1
    # PNG: each AOV mapped as a still's are, light AOVs through --tonemap and --exposure;
    # the expected images come from the frame's own EXR layers.
    depth = channels["Z"]
    layers = {
        "depth": depth,
        "normal": np.stack([channels[f"N.{c}"] for c in "XYZ"], -1),
        "direct": np.stack([channels[f"direct.{c}"] for c in "RGB"], -1),
    }
    for name, image in layers.items():
        png = gi.read_image(tmp_path / f"p_001.{name}.png")
        shown = display.aov_display(name, image, depth, "filmic", 1.0)
        expected = display.quantize8(shown if shown.ndim == 3 else shown[..., None]) / 255
        assert np.abs(png - expected).max() <= 1 / 255 + 1e-6, name
    # Depth is not all white: nearest white, farthest 15 % grey.
    shown_depth = gi.read_image(tmp_path / "p_001.depth.png")[..., 0]
    assert shown_depth.max() == 1.0 and shown_depth[depth > 0].min() < 0.2


def test_sequence_outputs_are_checked_before_the_first_frame(tmp_path):
    base = ["render", "cornell-anim", "--frames", "0:2", "--size", "16x12", "-q"]
    cases = [
        (["-o", "ok/f_%03d.exr", "--aov", "albdo"], "no AOV 'albdo'"),
        (["-o", "ok/f_%03d.exr", "-o", "/proc/gi/f_%03d.png"], "cannot write"),
        (["-o", "ok/f_%03d.exr", "-o", "ok/f_%03d.exr"], "written twice"),
    ]
    for extra, message in cases:
        p = run(*base, *extra, cwd=tmp_path)
        assert p.returncode == 2 and message in p.stderr, (extra, p.stderr)
        # Before, frame 0 was rendered and written first.
        assert not (tmp_path / "ok").exists(), extra


# -- 2. `.hdr` holds no single channel --------------------------------------------------------


def test_hdr_outputs_write_depth_as_grey_rgb(tmp_path, cornell):
    p = run(
        *("render", "cornell", "-o", "tm.hdr", "--aov", "all", "--method", "direct"),
        *("--size", "16x16", "-q"),
        cwd=tmp_path,
    )
    assert p.returncode == 0, p.stderr
    names = {"tm.hdr"} | {f"tm.{a}.hdr" for a in ("albedo", "normal", "position", "depth")}
    assert {f.name for f in tmp_path.iterdir()} == names | {"tm.direct.hdr"}
    r = gi.render(cornell, "direct", **small("direct"))
    gi.save_image(tmp_path / "d.hdr", r.depth)
    back = gi.read_image(tmp_path / "d.hdr")
    assert back.shape == (16, 16, 3)
    # RGBE keeps 8 bits of mantissa per channel; the three channels are the depth.
    assert np.allclose(back, r.depth[..., None], rtol=1e-2)


def test_a_failed_write_leaves_none_of_the_files(tmp_path, cornell, monkeypatch):
    r = gi.render(cornell, "direct", **small("direct"))
    writes = []
    real = io._write_tmp

    def third_fails(planned):
        writes.append(planned.path)
        if len(writes) == 3:
            raise gi.OutputError(planned.path, "disk full (simulated)")
        return real(planned)

    monkeypatch.setattr(io, "_write_tmp", third_fails)
    with pytest.raises(gi.OutputError, match="disk full"):
        gi.save_result(tmp_path / "x.png", r, ["albedo", "normal", "depth"])
    assert len(writes) == 3 and os.listdir(tmp_path) == []
    with pytest.raises(gi.SettingError, match="holds 3 channels, the image has 4"):
        gi.save_image(tmp_path / "a.hdr", np.zeros((2, 2, 4), np.float32))


# -- 3. Mitsuba <lookat> without up ----------------------------------------------------------


def test_mitsuba_lookat_without_up_takes_mitsubas_up(tmp_path):
    from gi.mitsuba import coordinate_system

    scene = """<scene version="3.0.0">
<sensor type="perspective"><transform name="to_world">
<lookat origin="0, 1, 4" target="0, 1, 0" up="0, 1, 0"/></transform>
<film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film>
</sensor>
<emitter type="spot"><transform name="to_world"><lookat origin="0, 2, 0" target="0, 0, 0"/>
</transform><float name="cutoff_angle" value="30"/></emitter>
<shape type="rectangle"/>
</scene>"""
    (tmp_path / "s.xml").write_text(scene)
    with pytest.warns(gi.AssetWarning, match="falls off"):  # the spot's falloff, named
        s = gi.load_scene(tmp_path / "s.xml")  # was refused: "up must not be parallel ..."
    assert s.light_count == 1
    r = gi.Renderer(s, "path", size=(8, 8), spp=1)
    assert r.describe("light", 0)["direction"] == pytest.approx([0, -1, 0], abs=1e-6)
    # Mitsuba 3's basis (Duff et al. 2017): orthonormal, right-handed with n.
    for n in ([0, -1, 0], [0, 0, -1], [0.48, 0.6, 0.64]):
        n = np.array(n, float)
        a, b = coordinate_system(n)
        assert np.allclose([a @ n, b @ n, a @ b], 0, atol=1e-12)
        assert np.allclose(np.cross(a, b), n)


# -- 4. the CLI shows the warnings of a scene that fails to load ----------------------------


def test_cli_prints_asset_warnings_when_loading_fails(tmp_path):
    (tmp_path / "m.obj").write_text("mtllib nonexist.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    desc = json.loads(gi.builtin_json("cornell"))
    desc["objects"].append({"shape": {"type": "mesh", "file": "m.obj"}})
    (tmp_path / "s.json").write_text(json.dumps(desc))
    p = run("render", "s.json", "-o", "x.png", "--size", "8x8", cwd=tmp_path)
    assert p.returncode == 2 and "material: required" in p.stderr
    assert "gi: warning:" in p.stderr and "mtllib nonexist.mtl: cannot read" in p.stderr


# -- 5. results without AOVs -----------------------------------------------------------------


def test_a_result_without_aovs_says_so(tmp_path, cornell):
    bare = gi.Renderer(cornell, "direct", **small("direct")).render()
    assert bare.aov_names() == ["radiance"] and "aovs: radiance>" in repr(bare)
    with pytest.raises(gi.SettingError, match="aovs=True"):
        gi.save_result(tmp_path / "x.exr", bare, ["albedo"])
    with pytest.raises(gi.SettingError, match="aovs=True"):
        gi.denoise(bare)
    with pytest.raises(gi.SettingError, match="extras=True"):
        bare.aov("direct")
    assert not list(tmp_path.iterdir())


# -- 6. Renderer.update / resize / render checks --------------------------------------------


@pytest.mark.parametrize(
    ("call", "error", "text"),
    [
        (lambda r: r.update(camera={"fov": float("nan")}), gi.SceneError, "camera.fov"),
        (lambda r: r.update(lights={0: {"position": [0, np.inf, 0]}}), gi.SceneError, "position"),
        (lambda r: r.update(objects=[{"translate": [0, 0, 0]}]), gi.SceneError, "objects"),
        (lambda r: r.update(objects={True: {"translate": [0, 0, 0]}}), gi.SceneError, "True"),
        (lambda r: r.update(camera={"width": 48}), gi.SceneError, "resize"),
        (lambda r: r.update(lights="x"), gi.SceneError, "lights"),
        (lambda r: r.resize(-5, 10), gi.SettingError, "width`: must be in 1..=16384, got -5"),
        (lambda r: r.resize("5", 10), gi.SettingError, "width`: must be an integer in 1..=16384"),
        (lambda r: r.resize(10, 2**40), gi.SettingError, "height"),
        (lambda r: r.render(seed=-1), gi.SettingError, "seed`: must be in 0..="),
        (lambda r: r.render(aovs="yes"), gi.SettingError, "aovs"),
        (lambda r: r.describe("thing"), gi.SettingError, "camera, light, object, material"),
    ],
)
def test_renderer_checks_name_the_field(cornell, call, error, text):
    r = gi.Renderer(cornell, "direct", **small("direct"))
    with pytest.raises(error) as e:
        call(r)
    assert text in str(e.value)
    assert r.render().radiance.shape == (16, 16, 3)  # nothing changed


def test_updates_take_numpy_and_change_light_types(cornell):
    r = gi.Renderer(cornell, "direct", **small("direct"))
    r.update(
        camera={"position": np.array([0.1, 1.0, 3.4])},
        lights={0: {"intensity": np.full(3, 2.0, np.float32)}},
        materials={"white": {"roughness": np.float64(0.5)}},
    )
    assert r.describe("camera")["position"] == pytest.approx([0.1, 1.0, 3.4])
    # A point light becomes a spot (its position and intensity kept) and back.
    r.update(lights={0: {"type": "spot", "direction": [0, -1, 0]}})
    spot = r.describe("light", 0)
    assert spot["type"] == "spot" and spot["intensity"] == [2.0, 2.0, 2.0]
    r.update(lights={0: {"type": "point"}})  # failed on the merged `direction`
    assert r.describe("light", 0) == {
        "type": "point",
        "position": spot["position"],
        "intensity": [2.0, 2.0, 2.0],
    }


def test_spot_angles_given_alone_fit(write_scene, cornell_desc):
    cornell_desc["lights"] = [
        {"type": "spot", "position": [0, 1.9, 0], "direction": [0, -1, 0], "intensity": [5] * 3}
        | extra
        for extra in ({"outer_angle": 20}, {"inner_angle": 40}, {})
    ]
    r = gi.Renderer(gi.load_scene(write_scene(cornell_desc)), "direct", **small("direct"))
    angles = [r.describe("light", i)[k] for i in range(3) for k in ("inner_angle", "outer_angle")]
    assert angles == pytest.approx([20 * 5 / 6, 20, 40, 48, 25, 30], abs=1e-3)
    # An update of one angle that would leave the other outside the cone moves it too.
    r.update(lights={2: {"outer_angle": 10}})
    assert r.describe("light", 2)["inner_angle"] == pytest.approx(10 * 5 / 6, abs=1e-3)
    r.update(lights={2: {"outer_angle": 60}})
    assert r.describe("light", 2)["inner_angle"] == pytest.approx(10 * 5 / 6, abs=1e-3)


# -- 7. object updates merge, and describe("object") ----------------------------------------


def test_object_updates_merge_and_describe_reads_them_back():
    r = gi.Renderer(gi.load_scene("cornell-anim"), "direct", **small("direct"))
    before = r.describe("object", "tall box")
    assert before["transform"] == {
        "translate": [-0.35, 0.6, -0.35],
        "rotate": [0.0, 20.0, 0.0],
        "scale": 1.0,
    }
    r.update(objects={"tall box": {"rotate": [0, 45, 0]}})
    after = r.describe("object", "tall box")
    # The box turned in place: it used to drop to the origin (the transform was reset).
    assert after["transform"]["translate"] == pytest.approx(before["transform"]["translate"])
    assert after["transform"]["rotate"] == pytest.approx([0, 45, 0], abs=1e-4)
    assert (
        after["matrix"][0][3] == pytest.approx(-0.35) and after["triangles"] == before["triangles"]
    )
    index = r.object_names.index("tall box")
    r.update(objects={index: {"matrix": np.diag([1.0, 2.0, 1.0, 1.0])}})
    scaled = r.describe("object", index)["transform"]
    assert scaled["scale"] == [1, 2, 1] and scaled["translate"] == scaled["rotate"] == [0, 0, 0]
    sheared = np.eye(4)
    sheared[0, 1] = 0.5
    r.update(objects={index: {"matrix": sheared}})
    described = r.describe("object", index)
    assert described["transform"] is None and described["matrix"] == sheared.tolist()
    with pytest.raises(gi.SceneError, match="shear"):
        r.update(objects={index: {"rotate": [0, 10, 0]}})
    with pytest.raises(gi.SettingError, match="named objects: 'floor'"):
        r.describe("object", "nope")


# -- 8. texture names as the scene file gives them ------------------------------------------


def test_texture_names_do_not_depend_on_how_the_scene_path_is_spelled(tmp_path, monkeypatch):
    sub = tmp_path / "sub"
    (sub / "tex").mkdir(parents=True)
    gi.save_image(sub / "tex" / "checker.png", np.indices((4, 4)).sum(0)[..., None] % 2 * [1, 1, 1])
    gi.save_image(sub / "rough.png", np.full((2, 2, 3), 0.5))
    desc = json.loads(gi.builtin_json("cornell"))
    desc["materials"]["white"]["roughness_texture"] = "rough.png"
    desc["materials"]["red"]["diffuse_texture"] = "tex/checker.png"
    (sub / "s.json").write_text(json.dumps(desc))
    monkeypatch.chdir(tmp_path)
    for spelling in ("sub/s.json", "./sub/../sub/s.json", str(sub / "s.json")):
        r = gi.Renderer(gi.load_scene(spelling), "direct", **small("direct"))
        assert r.describe("material", "red")["diffuse_texture"] == "tex/checker.png"
        assert r.describe("material", "white")["roughness_texture"] == "rough.png"
        r.update(materials={"green": {"diffuse_texture": "tex/checker.png"}})
        r.update(materials={"green": {"roughness_texture": "rough.png"}})
        with pytest.raises(gi.SceneError, match=r"loaded: rough.png, tex/checker.png"):
            r.update(materials={"green": {"diffuse_texture": "checker.png"}})


# -- 9. AOVs a method does not render --------------------------------------------------------


def test_cli_refuses_aovs_the_method_does_not_render(tmp_path):
    base = ["render", "cornell", "-o", "x.png", "--size", "8x8", "--spp", "1", "-q"]
    p = run(*base, "--aov", "caustics", cwd=tmp_path)
    assert p.returncode == 2 and "has no AOV 'caustics'" in p.stderr and "path" in p.stderr
    p = run(*base, "--aov", "noisy", cwd=tmp_path)
    assert p.returncode == 2 and "needs --denoise" in p.stderr
    p = run(*base, "--aov", "caustics", "--method", "path", cwd=tmp_path)
    assert p.returncode == 0, p.stderr
    assert (tmp_path / "x.caustics.png").exists()


# -- 10. writability is tried, not read from permission bits --------------------------------


def test_unwritable_outputs_fail_before_rendering(tmp_path):
    with pytest.raises(gi.OutputError, match="/proc is not writable"):
        io.check_output_path("/proc/x.png")
    # 100000 samples per pixel at 512x512 would render for hours: it fails at once.
    p = run("render", "cornell", "-o", "/proc/x.png", "--spp", "100000", timeout=60)
    assert p.returncode == 2 and "cannot write /proc/x.png" in p.stderr


# -- 11. messages ----------------------------------------------------------------------------


def test_messages_name_the_setting_and_what_it_allows(tmp_path, cornell, write_scene, cornell_desc):
    p = run("render", "cornell", "-o", str(tmp_path / "x.png"), "--spp", "-1")
    assert p.returncode == 2 and "`spp`: must be in 1..=" in p.stderr and "got -1" in p.stderr
    p = run("footprints", "cornell", "--photons", "-5")  # was an OverflowError's traceback
    assert p.returncode == 2 and "`photons`: must be in 1..=" in p.stderr
    with pytest.raises(gi.SettingError, match=r"spp`: must be an integer in 1\.\.=\d+, got \"4\""):
        gi.render(cornell, "path", spp="4")
    with pytest.raises(gi.SettingError, match="did you mean spp"):
        gi.render(cornell, "path", sp=4)
    with pytest.raises(gi.SettingError, match="did you mean photons"):
        gi.Renderer(cornell, "ispm", photon=4)
    with pytest.raises(gi.SettingError, match="clip, filmic, agx, aces"):
        gi.render(cornell, "path", size=(4, 4), spp=1).display(tonemap="bogus")
    assert gi.render("cornell", "path", size=(4, 4), spp=1).radiance.shape == (4, 4, 3)
    with pytest.raises(gi.SettingError, match="a gi.Scene, a built-in scene name"):
        gi.render(42)
    # No constant names or literal "(file)" fields.
    with pytest.raises(gi.SceneError) as e:
        gi.load_scene(tmp_path / "missing.json")
    assert "(file)" not in str(e.value) and e.value.field == "(file)"
    cornell_desc["objects"][0]["transform"] = {"translate": [0, 1e6, 0]}
    with pytest.raises(gi.SceneError) as e:
        gi.load_scene(write_scene(cornell_desc))
    assert "±100000 m" in str(e.value) and "MAX_" not in str(e.value)


def test_mesh_reader_failures_say_the_file_is_malformed(tmp_path, cornell_desc, write_scene):
    ply = trimesh.exchange.ply.export_ply(trimesh.creation.box(), encoding="ascii").decode()
    (tmp_path / "cut.ply").write_text(ply[:210])
    (tmp_path / "bad.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 5\n")
    for name in ("cut.ply", "bad.obj"):
        desc = json.loads(json.dumps(cornell_desc))
        desc["objects"].append({"shape": {"type": "mesh", "file": name}, "material": "white"})
        with pytest.raises(gi.SceneError) as e:
            gi.load_scene(write_scene(desc))
        kind = name.split(".")[1].upper()
        assert f"is not a valid {kind} file: it is truncated or malformed" in str(e.value)


# -- 13. scenes that render black ------------------------------------------------------------


def test_scenes_without_lights_or_objects_warn(tmp_path, cornell_desc, write_scene):
    dark = dict(cornell_desc, lights=[])
    with pytest.warns(gi.SceneWarning, match="no light source"):
        gi.Renderer(gi.load_scene(write_scene(dark)), "path", size=(4, 4), spp=1)
    empty = dict(cornell_desc, objects=[])
    with pytest.warns(gi.SceneWarning, match="no objects"):
        gi.Renderer(gi.load_scene(write_scene(empty)), "path", size=(4, 4), spp=1)
    p = run(
        "render",
        str(write_scene(dark, "dark.json")),
        "-o",
        "x.png",
        "--size",
        "4x4",
        "--method",
        "path",
        "--spp",
        "1",
        "-q",
        cwd=tmp_path,
    )
    assert p.returncode == 0 and "gi: warning:" in p.stderr and "no light source" in p.stderr


# -- 14. help, reprs, README -----------------------------------------------------------------


def test_methods_are_described_one_line_each():
    p = run("methods")
    lines = p.stdout.splitlines()
    assert p.returncode == 0 and len(lines) == len(gi.methods())
    for name, line in zip(gi.methods(), lines, strict=True):
        assert line.split()[0] == name and len(line.split()) > 5, line


def test_renderer_and_progressive_result_reprs_and_exr_header(tmp_path, cornell):
    r = gi.Renderer(cornell, "gather", progressive=True, **small("gather"))
    assert repr(r) == (
        "<gi.Renderer gather 16x16 of 'cornell', progressive (0 passes), 0 frames rendered>"
    )
    means = []
    result = r.render_progressive(passes=3, aovs=True, on_pass=means.append)
    assert "progressive (3 passes), 3 frames rendered" in repr(r)
    assert "3 passes of 1 spp" in repr(result)
    gi.save_result(tmp_path / "p.exr", result)
    spec = oiio.ImageInput.open(str(tmp_path / "p.exr")).spec()
    assert spec.getattribute("gi:passes") == 3 and spec.getattribute("gi:samples_per_pixel") == 3
    # The time of the mean image is that of all its passes (was the last pass's): each mean
    # adds its pass's time, and the earlier passes are a stage of their own.
    assert spec.getattribute("gi:render_seconds") == pytest.approx(result.stats.total_seconds)
    seconds = [m.stats.total_seconds for m in means]
    assert seconds[0] < seconds[1] < seconds[2] == result.stats.total_seconds
    assert dict(result.stats.stages)["earlier passes"] == pytest.approx(seconds[1])


def test_readme_material_update_changes_the_image(cornell):
    """The README's `r.update(camera=..., materials=...)` example, as written: its material
    change alone changes the image (roughness without a specular lobe changed nothing)."""
    text = (ROOT / "README.md").read_text()
    example = re.search(r"^r\.update\(camera=.*?\}\}\)", text, re.S | re.M)
    assert example, "the README's update example"

    class Capture:
        def update(self, **kwargs):
            self.kwargs = kwargs

    capture = Capture()
    exec(re.sub(r"#[^\n]*", "", example.group(0)), {"r": capture})
    r = gi.Renderer(cornell, "path", size=(16, 16), spp=4)
    before = r.render().radiance
    r.update(materials=capture.kwargs["materials"])
    assert np.abs(r.render().radiance - before).max() > 0.01


def test_environment_light_renders_in_gather(cornell_desc, write_scene):
    # Once refused by every method but `path` and `bidir` (a SettingError naming them);
    # issue 28: every method renders the environment, and what it adds is light.
    plain = gi.render(gi.load_scene(write_scene(cornell_desc)), "gather", size=(8, 8), seed=1)
    cornell_desc["environment"] = {"radiance": [0.6, 0.7, 1.0]}
    lit = gi.render(gi.load_scene(write_scene(cornell_desc)), "gather", size=(8, 8), seed=1)
    assert lit.radiance.mean() > plain.radiance.mean()


def test_ispm_choices_print_with_verbose_only(tmp_path):
    args = ["render", "cornell", "-o", "x.png", "--size", "8x8", "--spp", "1"]
    args += ["--photons", "2000"]
    quiet, verbose = run(*args, cwd=tmp_path), run(*args, "-v", cwd=tmp_path)
    assert quiet.returncode == verbose.returncode == 0
    assert "estimator" not in quiet.stderr and "first bounce" not in quiet.stderr
    assert "estimator " in verbose.stderr and "first bounce " in verbose.stderr


def test_odd_video_sizes_are_padded_with_a_warning(tmp_path):
    from test_animation import read_video

    args = ["render", "cornell-anim", "--frames", "0:2", "--method", "direct", "-q"]
    p = run(*args, "--size", "17x15", "-o", "v.mp4", cwd=tmp_path)
    assert p.returncode == 0, p.stderr
    assert "gi: warning:" in p.stderr and "padded to 18x16" in p.stderr
    frames, size = read_video(tmp_path / "v.mp4")
    assert size == (18, 16) and len(frames) == 2
    p = run(*args, "--size", "16x16", "-o", "w.mp4", cwd=tmp_path)
    assert p.returncode == 0 and "padded" not in p.stderr
