"""Mitsuba XML as Mitsuba 3 reads it: the version upgrade of files older than 2.0 (its
camelCase renames, `lookAt`, `diffuse_reflectance`, the UV offsets), sampled spectra in linear
sRGB (checked against values Mitsuba 3.9.1's `scalar_rgb` read back with `mi.traverse`), the
sensor's film and field of view, the `serialized` mesh format, and a typed error naming
file, line and property for each kind of picture-changing property gi does not render."""

import math
import struct
import warnings
import zlib

import numpy as np
import pytest

import gi
from gi.mitsuba import spectra
from gi.mitsuba.elements import parse_xml
from gi.mitsuba.translator import Translator
from gi.mitsuba.upgrade import camel_to_snake, upgrade

SENSOR = """<sensor type="perspective"><float name="fov" value="40"/>
<transform name="to_world"><lookat origin="0, 1, 4" target="0, 1, 0" up="0, 1, 0"/></transform>
<film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/></film>
</sensor>"""


def write(tmp_path, body, version="3.0.0", sensor=SENSOR):
    path = tmp_path / "s.xml"
    path.write_text(f'<scene version="{version}">\n{sensor}\n{body}\n</scene>\n')
    return path


def translate(path):
    t = Translator(path)
    t.run(parse_xml(path.read_bytes(), str(path)))
    return t


@pytest.mark.parametrize(
    "old, new",
    [
        ("toWorld", "to_world"),
        ("intIOR", "int_ior"),
        ("extIOR", "ext_ior"),
        ("fovAxis", "fov_axis"),
        ("sampleCount", "sample_count"),
        ("diffuseReflectance", "diffuse_reflectance"),
        ("specularReflectance", "specular_reflectance"),
        ("faceNormals", "face_normals"),
        ("uvscale", "uvscale"),
        ("maxDepth", "max_depth"),
        ("aBCd", "a_bcd"),
        ("already_snake", "already_snake"),
    ],
)
def test_camel_case_names_as_mitsuba_renames_them(old, new):
    assert camel_to_snake(old) == new


def test_upgrade_only_below_version_2():
    old = parse_xml(b'<scene version="0.5.0"><shape name="toWorld"/></scene>', "x")
    assert upgrade(old) and old.children[0].attrs["name"] == "to_world"
    new = parse_xml(b'<scene version="2.0.0"><shape name="toWorld"/></scene>', "x")
    assert not upgrade(new) and new.children[0].attrs["name"] == "toWorld"


def test_old_file_reads_as_its_mitsuba_3_spelling(tmp_path):
    """The same scene in 0.5 spelling (camelCase, `<lookAt>`, `diffuseReflectance` on a
    diffuse BSDF, `intIOR`, `fovAxis`, an ldrfilm with display settings) and
    in Mitsuba 3 spelling give the same scene description, without a warning."""
    old_sensor = """<sensor type="perspective"><float name="fov" value="30"/>
<string name="fovAxis" value="y"/><float name="nearClip" value="0.1"/>
<transform name="toWorld"><lookAt origin="0, 1, 4" target="0, 1, 0" up="0, 1, 0"/></transform>
<sampler type="sobol"><integer name="sampleCount" value="64"/></sampler>
<film type="ldrfilm"><integer name="width" value="24"/><integer name="height" value="16"/>
<boolean name="banner" value="false"/><float name="gamma" value="2.2"/>
<string name="tonemapMethod" value="gamma"/><rfilter type="tent"/></film></sensor>"""
    new_sensor = (
        old_sensor.replace("fovAxis", "fov_axis")
        .replace("nearClip", "near_clip")
        .replace("toWorld", "to_world")
        .replace("lookAt", "lookat")
        .replace("sampleCount", "sample_count")
        .replace("tonemapMethod", "tonemap_method")
    )
    old_body = """<bsdf type="diffuse" id="d">
<rgb name="diffuseReflectance" value="0.2, 0.4, 0.6"/></bsdf>
<bsdf type="dielectric" id="g"><float name="intIOR" value="1.33"/></bsdf>
<shape type="cube"><transform name="toWorld"><scale value="0.5"/></transform><ref id="d"/></shape>
<shape type="sphere"><float name="radius" value="0.3"/><ref id="g"/></shape>
<emitter type="point"><point name="position" x="0" y="2" z="2"/></emitter>"""
    new_body = (
        old_body.replace("diffuseReflectance", "reflectance")
        .replace("intIOR", "int_ior")
        .replace("toWorld", "to_world")
    )
    (tmp_path / "old").mkdir()
    (tmp_path / "new").mkdir()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        old = translate(write(tmp_path / "old", old_body, "0.5.0", old_sensor))
        new = translate(write(tmp_path / "new", new_body, "3.0.0", new_sensor))
    assert old.description() == new.description()
    assert old.materials["d"]["diffuse"] == pytest.approx([0.2, 0.4, 0.6])
    assert old.materials["g"]["ior"] == pytest.approx(1.33 / 1.000277)
    assert old.camera["fov"] == pytest.approx(30) and old.camera["width"] == 24


def test_uv_offsets_become_a_to_uv_transform():
    root = parse_xml(
        b'<scene version="0.4.0"><texture type="bitmap" name="reflectance">'
        b'<float name="uscale" value="4"/><float name="voffset" value="0.5"/></texture></scene>',
        "x",
    )
    upgrade(root)
    tex = root.children[0]
    assert [c.tag for c in tex.children] == ["transform"]
    xf = tex.children[0]
    assert xf.attrs["name"] == "to_uv"
    assert [(op.tag, op.attrs) for op in xf.children] == [
        ("translate", {"x": "0", "y": "0.5"}),
        ("scale", {"x": "4", "y": "1"}),
    ]


# Mitsuba 3.9.1 `scalar_rgb`'s `mi.traverse` of a diffuse BSDF's `reflectance` and an area
# emitter's `radiance` given these spectra (scripts/probe/mitsuba_spectra.py).
MITSUBA_SRGB = [
    ("reflectance", "400:0.78, 500:0.78, 600:0.78, 700:0.78", [0.7763668, 0.77981, 0.7760291]),
    ("radiance", "400:0, 500:8, 600:15.6, 700:18.4", [20.710836, 10.854634, 2.771152]),
    ("reflectance", "0.3", [0.3, 0.3, 0.3]),
    ("radiance", "2.0", [2.4095879, 1.896582, 1.8178321]),
    ("reflectance", "400:2, 700:2", [1.0, 1.0, 1.0]),
    ("radiance", "450:1, 460:5, 600:0.5", [0.0, 2.5405788, 1.9295087]),
]


@pytest.mark.parametrize("name, value, expected", MITSUBA_SRGB)
def test_spectra_match_mitsubas_rgb_variants(name, value, expected):
    """Reflectances: D65-weighted, clamped to [0, 1]; emitters: unweighted, unbounded (≥ 0);
    a uniform emitter spectrum is Mitsuba's purple-ish xyz_to_srgb(1, 1, 1) · value. Mitsuba
    stores float32: agreement to 1e-6 relative."""
    emitter = name == "radiance"
    if ":" in value:
        got = spectra.pairs_to_srgb(*spectra.parse_pairs(value), emitter, False)
    else:
        got = spectra.uniform_to_srgb(float(value), emitter)
    assert got == pytest.approx(expected, rel=1e-6, abs=1e-7)


def test_cbox_spectra_match_mitsuba():
    """The red wall of Mitsuba's own Cornell box (`cbox.xml`), as Mitsuba 3.9.1 reads it."""
    import re
    from pathlib import Path

    text = (Path(__file__).parent / "scenes/third_party/cbox/cbox.xml").read_text()
    red = re.search(r'id="red">\s*<spectrum name="reflectance" value="([^"]+)"', text).group(1)
    got = spectra.pairs_to_srgb(*spectra.parse_pairs(red), False, False)
    assert got == pytest.approx([0.49132004, 0.04922811, 0.0509219], rel=1e-6)


def test_spectrum_file_and_srgb_values(tmp_path):
    (tmp_path / "s.spd").write_text("# a flat spectrum\n400 0.5\n700 0.5\n")
    body = """<bsdf type="diffuse" id="a"><spectrum name="reflectance" filename="s.spd"/></bsdf>
<bsdf type="diffuse" id="b"><srgb name="reflectance" value="0.5, 0.5, 0.5"/></bsdf>
<shape type="cube"><ref id="a"/></shape><shape type="sphere"><ref id="b"/></shape>"""
    t = translate(write(tmp_path, body))
    flat = spectra.pairs_to_srgb(np.array([400.0, 700.0]), np.array([0.5, 0.5]), False, False)
    assert t.materials["a"]["diffuse"] == pytest.approx(flat.tolist())
    assert t.materials["b"]["diffuse"] == pytest.approx([0.21404] * 3, rel=1e-4)


# Mitsuba 3.9.1 `scalar_spectral`'s film (RGB) looking at an area emitter of `blackbody`
# radiance, 8×8 pixels at 256 spp (its spectral sampling's noise: 0.1-0.3% on the mean; the
# RGB variants refuse the plugin): the emitter's radiance in linear sRGB.
MITSUBA_BLACKBODY = [
    (2500, [159.27577, 59.378540, 10.754206]),
    (6500, [43905.969, 41448.324, 43673.773]),
]


@pytest.mark.parametrize("temperature, expected", MITSUBA_BLACKBODY)
def test_blackbody_matches_mitsubas_spectral_film(tmp_path, temperature, expected):
    """`<spectrum type="blackbody">`: Planck's radiance per nm over 360-830 nm through the
    CIE curves (gi.mitsuba.spectra), within 0.5% of Mitsuba's spectral render per channel
    (its noise 0.3% at most); a 0.x `<blackbody>` element stays an error (above)."""
    body = f"""<shape type="rectangle"><emitter type="area">
<spectrum name="radiance" type="blackbody"><float name="temperature" value="{temperature}"/>
</spectrum></emitter></shape>"""
    t = translate(write(tmp_path, body))
    (light,) = [m for m in t.materials.values() if any(m.get("emission", [0]))]
    assert light["emission"] == pytest.approx(expected, rel=5e-3)


def test_include_inside_an_element(tmp_path):
    """An `<include>` inside a shape gives the shape the included file's elements (its BSDF
    here), as Mitsuba 3.9.1 reads it (`mi.load_file` of these two files gives the sphere a
    SmoothDiffuse of reflectance 0.2, 0.4, 0.6); includes nest."""
    bsdf = '<bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.4, 0.6"/></bsdf>'
    (tmp_path / "inner.xml").write_text(f'<scene version="3.0.0">{bsdf}</scene>')
    (tmp_path / "part.xml").write_text(
        '<scene version="3.0.0"><include filename="inner.xml"/></scene>'
    )
    included = translate(
        write(tmp_path, '<shape type="sphere"><include filename="part.xml"/></shape>')
    )
    inline = translate(write(tmp_path, f'<shape type="sphere">{bsdf}</shape>'))
    assert list(included.materials.values()) == list(inline.materials.values())
    assert list(included.materials.values())[0]["diffuse"] == pytest.approx([0.2, 0.4, 0.6])


@pytest.mark.parametrize(
    "axis, fov, width, height, vertical",
    [
        ("x", 60, 32, 16, 2 * math.degrees(math.atan(math.tan(math.radians(30)) / 2))),
        ("y", 60, 32, 16, 60),
        ("smaller", 60, 32, 16, 60),
        ("larger", 60, 32, 16, 2 * math.degrees(math.atan(math.tan(math.radians(30)) / 2))),
        ("smaller", 60, 16, 32, 2 * math.degrees(math.atan(math.tan(math.radians(30)) * 2))),
        (
            "diagonal",
            60,
            32,
            16,
            2 * math.degrees(math.atan(math.tan(math.radians(30)) * 16 / math.hypot(32, 16))),
        ),
    ],
)
def test_fov_axis(tmp_path, axis, fov, width, height, vertical):
    sensor = f"""<sensor type="perspective"><float name="fov" value="{fov}"/>
<string name="fov_axis" value="{axis}"/>
<film type="hdrfilm"><integer name="width" value="{width}"/>
<integer name="height" value="{height}"/></film>
</sensor>"""
    t = translate(write(tmp_path, '<shape type="sphere"/>', sensor=sensor.replace("\n", " ")))
    assert t.camera["fov"] == pytest.approx(vertical)


def test_focal_length_is_a_diagonal_fov(tmp_path):
    """No `fov`: Mitsuba 3's 50 mm default, a diagonal fov over 36×24 mm film."""
    sensor = """<sensor type="perspective"><film type="hdrfilm">
<integer name="width" value="30"/><integer name="height" value="20"/></film></sensor>"""
    t = translate(
        write(
            tmp_path,
            '<shape type="sphere"><point name="center" x="0" y="0" z="5"/></shape>',
            sensor=sensor,
        )
    )
    diag = 2 * math.atan(math.hypot(36, 24) / 100)  # 50 mm
    vertical = 2 * math.atan(math.tan(diag / 2) * 20 / math.hypot(30, 20))
    assert t.camera["fov"] == pytest.approx(math.degrees(vertical))


def serialized_bytes(shapes):
    """A Mitsuba serialized file (version 4, single precision) of (vertices, faces) shapes."""
    out, offsets = b"", []
    for v, f in shapes:
        body = struct.pack("<I", 0x1000) + b"mesh\0" + struct.pack("<QQ", len(v), len(f))
        body += np.asarray(v, "<f4").tobytes() + np.asarray(f, "<u4").tobytes()
        offsets.append(len(out))
        out += struct.pack("<HH", 0x041C, 4) + zlib.compress(body)
    return out + struct.pack(f"<{len(offsets)}Q", *offsets) + struct.pack("<I", len(offsets))


def test_serialized_shapes(tmp_path):
    quad = ([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], [[0, 1, 2], [0, 2, 3]])
    tri = ([[0, 0, 0], [2, 0, 0], [0, 2, 0]], [[0, 1, 2]])
    (tmp_path / "m.serialized").write_bytes(serialized_bytes([quad, tri]))
    body = """<shape type="serialized"><string name="filename" value="m.serialized"/>
<integer name="shape_index" value="1"/>
<transform name="to_world"><translate z="-1"/></transform></shape>
<shape type="serialized"><string name="filename" value="m.serialized"/></shape>"""
    t = translate(write(tmp_path, body))
    sizes = sorted(len(t.meshes[o["shape"]["file"]][1]) for o in t.objects)
    assert sizes == [1, 2]
    bad = body.replace('value="1"', 'value="2"')
    with pytest.raises(gi.SceneError, match="out of range") as e:
        gi.load_scene(write(tmp_path, bad))
    assert e.value.field == '<shape type="serialized"> (line 6)'
    data = serialized_bytes([quad, tri])
    (tmp_path / "m.serialized").write_bytes(data[:30] + data[-12:])  # a truncated shape
    with pytest.raises(gi.SceneError, match="cannot read m.serialized"):
        gi.load_scene(write(tmp_path, body))


# One per kind of property that changes the picture: (body, sensor or None, element, line,
# property named in the reason).
CROP = SENSOR.replace(
    '<integer name="height" value="16"/>',
    '<integer name="height" value="16"/><integer name="crop_width" value="8"/>',
)
PRINCIPAL = SENSOR.replace(
    '<float name="fov" value="40"/>',
    '<float name="fov" value="40"/><float name="principal_point_offset_x" value="0.1"/>',
)
NEAR = SENSOR.replace(
    '<float name="fov" value="40"/>',
    '<float name="fov" value="40"/><float name="near_clip" value="3.5"/>',
)
FAR = SENSOR.replace(
    '<float name="fov" value="40"/>',
    '<float name="fov" value="40"/><float name="far_clip" value="2"/>',
)
APERTURE = SENSOR.replace(
    '<float name="fov" value="40"/>',
    '<float name="fov" value="40"/><float name="aperture_radius" value="0.1"/>',
)


@pytest.mark.parametrize(
    "body, sensor, element, line, prop",
    [
        (
            '<shape type="sphere"><boolean name="flip_uv" value="true"/></shape>',
            None,
            '<boolean name="flip_uv">',
            6,
            "flip_uv",
        ),
        (
            '<bsdf type="diffuse" id="d"><float name="roughness" value="0.3"/></bsdf>',
            None,
            '<float name="roughness">',
            6,
            "roughness",
        ),
        (
            '<emitter type="point"><float name="scale" value="2"/></emitter>',
            None,
            '<float name="scale">',
            6,
            "scale",
        ),
        (
            '<shape type="cube"><transform name="to_world"><skew value="1"/></transform></shape>',
            None,
            "<skew>",
            6,
            "transform",
        ),
        (
            '<shape type="sphere"/>',
            APERTURE,
            '<float name="aperture_radius">',
            1,
            "aperture_radius",
        ),
        ('<shape type="sphere"/>', CROP, '<integer name="crop_width">', 3, "crop"),
        (
            '<shape type="sphere"/>',
            PRINCIPAL,
            '<float name="principal_point_offset_x">',
            1,
            "principal_point_offset_x",
        ),
        ('<shape type="sphere"/>', NEAR, '<float name="near_clip">', 1, "near_clip"),
        ('<shape type="sphere"/>', FAR, '<float name="far_clip">', 1, "far_clip"),
        (
            '<bsdf type="diffuse" id="d"><texture type="bitmap" name="reflectance">'
            '<transform name="to_uv"><scale x="2"/></transform></texture></bsdf>',
            None,
            '<transform name="to_uv">',
            6,
            "to_uv",
        ),
        (
            '<emitter type="point"><blackbody name="intensity" temperature="5000"/></emitter>',
            None,
            '<blackbody name="intensity">',
            6,
            "blackbody",
        ),
        (
            '<emitter type="point"><spectrum name="intensity" type="blackbody">'
            '<float name="temperature" value="5000"/><float name="scale" value="2"/>'
            "</spectrum></emitter>",
            None,
            '<float name="scale">',
            6,
            "scale",
        ),
        (
            '<shape type="sphere"><medium type="homogeneous" name="interior"/></shape>',
            None,
            '<medium type="homogeneous">',
            6,
            "medium",
        ),
        (
            '<bsdf type="roughconductor" id="c"><float name="ext_eta" value="1.5"/></bsdf>',
            None,
            '<float name="ext_eta">',
            6,
            "ext_eta",
        ),
    ],
)
def test_picture_changing_properties_are_errors(tmp_path, body, sensor, element, line, prop):
    path = write(tmp_path, body, sensor=SENSOR if sensor is None else sensor.replace("\n", " "))
    if sensor is not None:  # the sensor on one line: its properties are on line 2
        line = 2
    with pytest.raises(gi.SceneError) as e:
        gi.load_scene(path)
    assert e.value.file == str(path)
    assert e.value.field == f"{element} (line {line})", e.value.field
    assert prop in str(e.value), str(e.value)


def test_cosmetic_settings_load_silently(tmp_path):
    """Output and sampling settings (film encodings, banner, the integrator, sampler, pixel
    filter, an emitter's sampling weight, a pinhole's focus distance) change no radiance."""
    sensor = SENSOR.replace(
        "</film>",
        '<string name="pixel_format" value="rgba"/><boolean name="banner" value="false"/>'
        '<boolean name="high_quality_edges" value="true"/><rfilter type="gaussian"/></film>'
        '<float name="focus_distance" value="3"/><sampler type="stratified"/>',
    )
    body = """<integrator type="volpath"><integer name="max_depth" value="8"/></integrator>
<shape type="sphere"/><emitter type="point"><float name="sampling_weight" value="2"/></emitter>"""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        gi.load_scene(write(tmp_path, body, sensor=sensor))


def test_clip_planes_that_cut_nothing_load(tmp_path):
    """A camera inside a closed room (the default near plane, 0.01, cuts nothing there) and
    a far plane beyond everything: no error (only geometry the planes would cut is)."""
    sensor = SENSOR.replace(
        '<float name="fov" value="40"/>',
        '<float name="fov" value="40"/><float name="far_clip" value="20"/>',
    )
    body = '<shape type="cube"><transform name="to_world"><scale value="5"/></transform></shape>'
    translate(write(tmp_path, body, sensor=sensor))


def test_include_errors_name_the_included_file(tmp_path):
    """An error in an included file names that file and its line; a file including itself
    is refused, not followed forever."""
    (tmp_path / "part.xml").write_text(
        '<scene version="0.5.0">\n<shape type="sphere">\n'
        '<float name="noSuchThing" value="1"/></shape>\n</scene>\n'
    )
    path = write(tmp_path, '<include filename="part.xml"/>')
    with pytest.raises(gi.SceneError) as e:
        gi.load_scene(path)
    # The part's own 0.5 version upgraded its camelCase name.
    assert e.value.file == str(tmp_path / "part.xml")
    assert e.value.field == '<float name="no_such_thing"> (line 3)'
    (tmp_path / "loop.xml").write_text(
        '<scene version="3.0.0"><include filename="loop.xml"/></scene>'
    )
    with pytest.raises(gi.SceneError, match="nested more than"):
        gi.load_scene(write(tmp_path, '<include filename="loop.xml"/>'))
