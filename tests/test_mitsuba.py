"""Mitsuba 3 XML scenes: the Cornell box written as Mitsuba XML renders as the same scene in
gi's JSON; what gi cannot render is a typed error naming the element and its line."""

import json
import math
import subprocess
import sys
import warnings

import numpy as np
import pytest
import trimesh

import gi

W, H = 48, 32


def ops(transform, pre=""):
    """gi's transform (scale, rotate x, y, z in degrees, translate) as Mitsuba operations."""
    out = [pre] if pre else []
    scale = transform.get("scale", 1)
    if scale != 1:
        s = scale if isinstance(scale, list) else [scale] * 3
        out.append(f'<scale x="{s[0]}" y="{s[1]}" z="{s[2]}"/>')
    for axis, angle in zip("xyz", transform.get("rotate", [0, 0, 0]), strict=True):
        if angle:
            out.append(f'<rotate {axis}="1" angle="{angle}"/>')
    if "translate" in transform:
        out.append('<translate value="{}, {}, {}"/>'.format(*transform["translate"]))
    return "".join(out)


def cornell_as_mitsuba(desc):
    """The built-in Cornell box written by hand-style Mitsuba XML: ids and refs, a `default`
    parameter, a twosided BSDF, rectangles and cubes with to_world transforms."""
    cam = desc["camera"]
    # gi's fov is vertical; Mitsuba's default fov_axis is x.
    fov_x = math.degrees(2 * math.atan(math.tan(math.radians(cam["fov"]) / 2) * W / H))
    light = desc["lights"][0]
    xml = [
        '<scene version="3.0.0">',
        '  <default name="spp" value="16"/>',
        f'  <default name="width" value="{W}"/>',
        '  <integrator type="path"><integer name="max_depth" value="8"/></integrator>',
        '  <sensor type="perspective">',
        f'    <float name="fov" value="{fov_x}"/>',
        '    <transform name="to_world">',
        '      <lookat origin="{}, {}, {}" target="{}, {}, {}" up="0, 1, 0"/>'.format(
            *cam["position"], *cam["look_at"]
        ),
        "    </transform>",
        '    <sampler type="independent"><integer name="sample_count" value="$spp"/></sampler>',
        '    <film type="hdrfilm">',
        '      <integer name="width" value="$width"/>',
        f'      <integer name="height" value="{H}"/>',
        "    </film>",
        "  </sensor>",
    ]
    for name, m in desc["materials"].items():
        rgb = ", ".join(map(str, m["diffuse"]))
        inner = f'<bsdf type="diffuse"><rgb name="reflectance" value="{rgb}"/></bsdf>'
        if name == "red":
            xml.append(f'  <bsdf type="twosided" id="{name}">{inner}</bsdf>')
        else:
            xml.append(inner.replace('type="diffuse"', f'type="diffuse" id="{name}"', 1))
    for obj in desc["objects"]:
        shape, xf = obj["shape"], obj.get("transform", {})
        if shape["type"] == "quad":
            sx, sz = shape["size"]
            # Mitsuba's rectangle is [-1, 1]² in the xy plane facing +z; gi's quad lies in
            # xz facing +y: scale, then turn -90° about x.
            pre = f'<scale x="{sx / 2}" y="{sz / 2}"/><rotate x="1" angle="-90"/>'
            kind = "rectangle"
        else:
            pre = '<scale value="{}, {}, {}"/>'.format(*(s / 2 for s in shape["size"]))
            kind = "cube"
        xml.append(
            f'  <shape type="{kind}"><transform name="to_world">{ops(xf, pre)}</transform>'
            f'<ref id="{obj["material"]}"/></shape>'
        )
    xml.append(
        '  <emitter type="point"><point name="position" value="{}, {}, {}"/>'
        '<rgb name="intensity" value="{}, {}, {}"/></emitter>'.format(
            *light["position"], *light["intensity"]
        )
    )
    xml.append("</scene>")
    return "\n".join(xml)


def test_mitsuba_cornell_box_matches_the_json_scene(tmp_path, cornell_desc):
    (tmp_path / "cornell.xml").write_text(cornell_as_mitsuba(cornell_desc))
    cornell_desc["camera"].update(width=W, height=H)
    (tmp_path / "cornell.json").write_text(json.dumps(cornell_desc))
    xml = gi.load_scene(tmp_path / "cornell.xml")
    ref = gi.load_scene(tmp_path / "cornell.json")
    assert (xml.width, xml.height) == (W, H)
    assert xml.triangle_count == ref.triangle_count and xml.light_count == 1
    a = gi.render(xml, "path", spp=16, seed=3)
    b = gi.render(ref, "path", spp=16, seed=3)
    # First hits through pixel centres: the same geometry and materials up to float
    # rounding, so depth and albedo agree except where a pixel centre lands on an edge
    # between two walls and rounding picks the other wall (8 of 1536 pixels here; at most 2%).
    close = np.isclose(a.depth, b.depth, rtol=1e-4, atol=1e-5)
    same = close & (np.abs(a.albedo - b.albedo).max(axis=-1) < 1e-4)
    assert same.mean() > 0.98, same.mean()
    # Radiance: 16 spp path tracing, RNG streams may differ where the triangulations do
    # (each quad's diagonal). Per-channel means within 3% (the noise of the mean of 1536
    # pixels at 16 spp is below 1%), and 4x4-block means within 15%.
    ma, mb = a.radiance.mean(axis=(0, 1)), b.radiance.mean(axis=(0, 1))
    assert np.allclose(ma, mb, rtol=0.03), (ma, mb)
    ba = a.radiance.reshape(H // 4, 4, W // 4, 4, 3).mean(axis=(1, 3))
    bb = b.radiance.reshape(H // 4, 4, W // 4, 4, 3).mean(axis=(1, 3))
    assert np.abs(ba - bb).mean() < 0.15 * bb.mean()


def test_gi_render_reads_mitsuba_xml(tmp_path, cornell_desc):
    scene = tmp_path / "cornell.xml"
    scene.write_text(cornell_as_mitsuba(cornell_desc))
    out = tmp_path / "c.png"
    p = subprocess.run(
        [sys.executable, "-m", "gi.cli", "render", str(scene), "-o", str(out), "--spp", "1",
         "--size", "16x16", "-q"],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert p.returncode == 0 and p.stderr == "", p.stderr
    assert gi.read_image(out).shape == (16, 16, 3)


SENSOR = """<sensor type="perspective"><float name="fov" value="40"/>
<transform name="to_world"><lookat origin="0, 1, 4" target="0, 1, 0" up="0, 1, 0"/></transform>
<film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/></film>
</sensor>"""


def write(tmp_path, body):
    path = tmp_path / "s.xml"
    path.write_text(f'<scene version="3.0.0">\n{SENSOR}\n{body}\n</scene>\n')
    return path


@pytest.mark.parametrize(
    "body, element, line",
    [
        ('<bsdf type="principled" id="g"/>', '<bsdf type="principled">', 6),
        ('<shape type="serialized"/>', '<shape type="serialized">', 6),
        (
            '<shape type="cube">\n<emitter type="point"/></shape>',
            '<emitter type="point">',
            7,
        ),
        ('<emitter type="area"/>', '<emitter type="area">', 6),
        ('<emitter type="sunsky"/>', '<emitter type="sunsky">', 6),
        ('<shape type="cube"><ref id="missing"/></shape>', "<ref>", 6),
        (
            '<shape type="sphere"><float name="radius" value="$r"/></shape>',
            '<float name="radius">',
            6,
        ),
        ("<volume/>", "<volume>", 6),
    ],
)
def test_unsupported_elements_are_typed_errors_naming_element_and_line(
    tmp_path, body, element, line
):
    with pytest.raises(gi.SceneError) as e:
        gi.load_scene(write(tmp_path, body))
    assert e.value.field == f"{element} (line {line})", e.value.field
    assert e.value.file.endswith("s.xml")


def test_malformed_xml_names_the_line(tmp_path):
    with pytest.raises(gi.SceneError) as e:
        gi.load_scene(write(tmp_path, '<shape type="cube">\n<bsdf type="diffuse">\n</shape>'))
    assert "(line 8" in e.value.field


def test_other_sensors_are_errors(tmp_path):
    path = tmp_path / "s.xml"
    path.write_text('<scene version="3.0.0">\n  <sensor type="thinlens"/>\n</scene>')
    with pytest.raises(gi.SceneError) as e:
        gi.load_scene(path)
    assert e.value.field == '<sensor type="thinlens"> (line 2)'


def test_bsdf_mapping(tmp_path):
    body = """<bsdf type="roughplastic" id="p">
<rgb name="diffuse_reflectance" value="0.5, 0.2, 0.1"/><float name="alpha" value="0.04"/></bsdf>
<bsdf type="conductor" id="gold"><string name="material" value="Au"/></bsdf>
<bsdf type="dielectric" id="glass"><string name="int_ior" value="water"/></bsdf>
<shape type="sphere"><ref id="p"/></shape>
<shape type="cube"><ref id="gold"/></shape>
<shape type="rectangle"><ref id="glass"/></shape>
<emitter type="spot"><transform name="to_world"><lookat origin="0, 3, 0" target="0, 0, 0"
up="0, 0, 1"/></transform><float name="cutoff_angle" value="30"/></emitter>"""
    from gi.mitsuba import _Translator, parse_xml

    path = write(tmp_path, body)
    t = _Translator(path)
    t.run(parse_xml(path.read_bytes(), str(path)))
    # Mitsuba's models map onto gi's (docs/scene-format.md), with nothing approximated.
    assert '<bsdf type="roughplastic"> (line 6)' not in t.notes
    m = t.materials
    assert m["p"]["diffuse"] == pytest.approx([0.5, 0.2, 0.1])
    assert m["p"]["roughness"] == pytest.approx(0.2)  # sqrt(alpha)
    assert m["p"]["distribution"] == "beckmann"  # Mitsuba's default
    assert m["p"]["coating_ior"] == pytest.approx(1.49 / 1.000277)  # polypropylene in air
    assert m["p"]["specular"] == [1, 1, 1] and m["p"]["coating_nonlinear"] is False
    assert m["gold"]["conductor_eta"] == pytest.approx([0.143036, 0.375307, 1.44205])
    assert m["gold"]["conductor_k"] == pytest.approx([3.983, 2.38556, 1.60336])
    assert m["gold"]["specular"] == [1, 1, 1] and m["gold"]["diffuse"] == [0, 0, 0]
    assert m["glass"]["ior"] == pytest.approx(1.333 / 1.000277)
    assert m["glass"]["transmission"] == [1, 1, 1]
    spot = t.lights[0]
    assert spot["direction"] == pytest.approx([0, -1, 0])
    assert (spot["inner_angle"], spot["outer_angle"]) == (22.5, 30.0)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scene = gi.load_scene(path)
    # The spot's falloff is the one approximation here; the BSDFs have none.
    assert [str(w.message) for w in caught if "spot" not in str(w.message)] == []
    assert scene.triangle_count > 12 + 2


def test_bitmap_texture_is_rendered_as_a_texture(tmp_path):
    """A rectangle facing the camera with a bitmap reflectance, red on the image's left half
    and black on its right: the albedo shows both halves (the mean colour used to
    be taken instead, with a warning)."""
    texture = np.zeros((4, 4, 3), np.float32)
    texture[:, :2] = [1, 0, 0]
    gi.save_image(tmp_path / "t.exr", texture)
    body = """<shape type="rectangle">
<transform name="to_world"><translate x="0" y="1" z="0"/></transform>
<bsdf type="diffuse"><texture type="bitmap" name="reflectance">
<string name="filename" value="t.exr"/></texture></bsdf></shape>
<emitter type="point"><point name="position" x="0" y="1" z="3"/></emitter>"""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        scene = gi.load_scene(write(tmp_path, body))
    r = gi.render(scene, "path", spp=1, seed=1, size=(32, 32))
    hit = r.depth > 0
    cols = np.nonzero(hit.any(axis=0))[0]
    mid = (cols.min() + cols.max()) // 2
    left = r.albedo[:, cols.min() + 1 : mid - 1][hit[:, cols.min() + 1 : mid - 1]]
    right = r.albedo[:, mid + 2 : cols.max()][hit[:, mid + 2 : cols.max()]]
    # Bilinear filtering blends the halves within half a texel of their borders (the
    # texture repeats, so the outer edges too): medians, not every pixel.
    assert len(left) > 10 and np.median(left[:, 0]) > 0.95, left.mean(0)
    assert len(right) > 10 and np.median(right[:, 0]) < 0.05, right.mean(0)
    assert np.allclose(left[:, 1:], 0) and np.allclose(right[:, 1:], 0)


def test_obj_shape_with_bitmap_texture_flat_shading(tmp_path):
    trimesh.creation.box(extents=(1, 1, 1)).export(tmp_path / "box.obj", include_normals=False)
    gi.save_image(tmp_path / "t.exr", np.full((2, 2, 3), 0.5, np.float32))
    body = """<shape type="obj"><string name="filename" value="box.obj"/>
<boolean name="face_normals" value="true"/>
<bsdf type="diffuse"><texture type="bitmap" name="reflectance">
<string name="filename" value="t.exr"/></texture></bsdf></shape>
<emitter type="point"><point name="position" x="0" y="1" z="3"/></emitter>"""
    scene = gi.load_scene(write(tmp_path, body))
    r = gi.render(scene, "path", spp=1, seed=1)
    seen = r.albedo[r.depth > 0]
    assert len(seen) > 10 and np.allclose(seen, 0.5, atol=1e-3)
    # face_normals: flat shading, as in Mitsuba (two faces in view from this camera).
    assert len(np.unique(np.round(r.normal[r.depth > 0], 3), axis=0)) <= 3


def test_unknown_properties_are_errors_naming_element_and_line(tmp_path):
    """A property gi does not read may change the picture: an error, not a warning."""
    body = '<shape type="cube"><float name="weird" value="1"/></shape>'
    with pytest.raises(gi.SceneError) as e:
        gi.load_scene(write(tmp_path, body))
    assert e.value.field == '<float name="weird"> (line 6)'
    assert "`weird`" in e.value.reason
