"""Shapes: each an object, an instance of a mesh in its local frame placed by a ``matrix``
transform, so that shapes that load the same file with the same options, equal built-in
shapes, and the shapes of a ``<shapegroup>`` placed by ``<shape type="instance">`` share
one mesh."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from gi._placement import first_bad_placement
from gi.meshes import load_mesh
from gi.mitsuba.bsdfs import bsdf
from gi.mitsuba.elements import Element
from gi.mitsuba.emitters import area_emitter
from gi.mitsuba.transforms import transform

if TYPE_CHECKING:
    from gi.mitsuba.translator import Translator

Props = dict[str, Element]
# Vertices, faces, normals (or None), UVs (or None) of a mesh in its local frame.
Built = tuple[Any, Any, Any, Any]

# The properties each shape reads (a nested <bsdf>/<emitter> is a child, not a property).
COMMON = {"to_world", "flip_normals", "bsdf"}
KNOWN = {
    "obj": COMMON | {"filename", "face_normals", "flip_tex_coords"},
    "ply": COMMON | {"filename", "face_normals"},
    "serialized": COMMON | {"filename", "face_normals", "shape_index"},
    "rectangle": COMMON,
    "cube": COMMON,
    "disk": COMMON,
    "sphere": COMMON | {"center", "radius"},
}


def shape(t: Translator, el: Element, parent: np.ndarray | None = None) -> None:
    """A shape as an object: its mesh (shared by equal shapes) placed by ``to_world``
    (after ``parent``, the instance's transform, for a shape of a shapegroup)."""
    kind = el.attrs.get("type")
    if kind == "instance":
        instance(t, el)
        return
    props = t.props(el)
    xf = transform(t, props.get("to_world"))
    if parent is not None:
        xf = parent @ xf
    key, smooth, local = shape_mesh(t, el, kind, props)
    material, emitter = None, None
    for c in el.children:
        target = t.resolve(c) if c.tag == "ref" else c
        if target.tag == "bsdf":
            material = bsdf(t, target)
        elif target.tag == "emitter":
            if target.attrs.get("type") != "area":
                raise t.error(target, "a shape's emitter must be an `area` emitter")
            emitter = target
        elif c.tag == "ref":
            raise t.error(c, f"refers to a <{target.tag}>, not a <bsdf> or <emitter>")
    if material is None:  # Mitsuba's default BSDF
        material = bsdf(t, Element("bsdf", {"type": "diffuse"}, el.line))
    if emitter is not None:
        material = area_emitter(t, el, emitter, material)
    m = xf @ local
    check_matrix(t, props.get("to_world", el), m)
    if material in t.bumps:
        from gi.mitsuba.layers import bake_bump

        material = bake_bump(t, material, key, m)
    if material in t.normal_maps:
        from gi.mitsuba.layers import orient_normal_map

        material = orient_normal_map(t, material, key, m)
    obj: dict[str, Any] = {
        "shape": {"type": "mesh", "file": key},
        "material": material,
        "transform": {"matrix": m[:3].tolist()},
    }
    if smooth is not None:
        obj["smooth"] = smooth
    t.objects.append(obj)


def shape_mesh(
    t: Translator, el: Element, kind: str | None, props: Props
) -> tuple[str, bool | None, np.ndarray]:
    """The key of a shape's mesh in ``t.meshes`` (added the first time: a file with its
    options, or a built-in shape in its local frame), its smoothing, and the matrix that
    places the built-in's parameters (a sphere's ``center`` and ``radius``)."""
    smooth: bool | None = None
    local = np.eye(4)
    build: Callable[[], Built]
    if kind in ("obj", "ply", "serialized"):
        key, smooth, build = mesh_file(t, el, kind, props)
    elif kind in BUILT_INS:
        key, build = kind, BUILT_INS[kind]
        if kind == "sphere":
            r = t.float(el, props, "radius", 1.0)
            local[:3, :3] *= r
            local[:3, 3] = t.vec3(props["center"]) if "center" in props else np.zeros(3)
    else:
        raise t.error(
            el, "unsupported shape (gi reads obj, ply, serialized, rectangle, cube, disk, sphere)"
        )
    t.refuse_unknown(props, KNOWN[kind])
    flip = t.boolean(props, "flip_normals", False)
    if flip:
        key += " (flip_normals)"
    if key not in t.meshes:
        v, f, n, uv = build()
        n = None if n is not None and not len(n) else n
        f = np.asarray(f, np.int64)
        if flip:
            f = f[:, [0, 2, 1]]
            n = None if n is None else -np.asarray(n)
        t.meshes[key] = (
            np.ascontiguousarray(v, np.float32),
            np.ascontiguousarray(f, np.uint32),
            None if n is None else np.ascontiguousarray(n, np.float32),
            None,
            None,
            None if uv is None else np.ascontiguousarray(uv, np.float32),
        )
    return key, smooth, local


def mesh_file(
    t: Translator, el: Element, kind: str, props: Props
) -> tuple[str, bool | None, Callable[[], Built]]:
    """An ``obj``/``ply``/``serialized`` shape: its file read once, its smoothing as
    Mitsuba's (``face_normals`` shades flat; a file without normals, smooth)."""
    file = t.string(props, "filename", "")
    key = f"{kind}:{file}"
    if kind == "serialized":
        index = int(t.float(el, props, "shape_index", 0))
        key += f"#{index}"
    if kind == "obj" and not t.boolean(props, "flip_tex_coords", True):
        key += " (flip_tex_coords=false)"
    if key not in t.files:
        t.files[key] = read_mesh_file(t, el, kind, props, file)
    built = t.files[key]
    smooth: bool | None = None
    if t.boolean(props, "face_normals", False) or (built[2] is not None and not len(built[2])):
        smooth = False  # asked for, or a serialized shape stored with face normals
    elif built[2] is None:
        smooth = True
    return key, smooth, lambda: built


def read_mesh_file(t: Translator, el: Element, kind: str, props: Props, file: str) -> Built:
    """Vertices, faces, normals and UVs of a mesh file (OBJ UVs with v flipped, as Mitsuba's
    default ``flip_tex_coords``; unflipped when it is false)."""
    field = f"{el.label} filename"
    if kind == "serialized":
        from gi.mitsuba.serialized import SerializedError, read_serialized

        index = int(t.float(el, props, "shape_index", 0))
        try:
            return read_serialized(t.file_path(el, file), index)
        except (OSError, SerializedError) as e:
            raise t.error(el, f"cannot read {file}: {e}") from None
    v, f, n, _m, _fm, uv = load_mesh(t.file_path(el, file), el.file or t.file, field, t.textures)
    if kind == "obj" and uv is not None and not t.boolean(props, "flip_tex_coords", True):
        uv = np.array(uv, copy=True)
        uv[:, 1] = 1.0 - uv[:, 1]
    return v, f, n, uv


def rectangle() -> Built:
    """Mitsuba's rectangle: [-1, 1]² in the xy plane facing +z, uv = ((x + 1)/2, (y + 1)/2)
    as Mitsuba's: v runs up +y, so the image's first row lies along y = -1 (Mitsuba shows
    a bitmap upside down on an unrotated rectangle seen from +z, and so does gi)."""
    v = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], np.float64)
    uv = (v[:, :2] + 1) / 2
    return v, np.array([[0, 1, 2], [0, 2, 3]]), np.tile([0.0, 0.0, 1.0], (4, 1)), uv


def _cube() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mitsuba's cube: [-1, 1]³, outward faces with flat normals."""
    verts, faces, normals = [], [], []
    for axis in range(3):
        for sign in (-1.0, 1.0):
            n = np.zeros(3)
            n[axis] = sign
            u, w = np.roll(np.eye(3), -axis, axis=0)[1:] * np.array([[1], [sign]])
            base = len(verts)
            for a, b in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                verts.append(n + a * u + b * w)
                normals.append(n)
            faces += [[base, base + 1, base + 2], [base, base + 2, base + 3]]
    return np.array(verts), np.array(faces), np.array(normals)


DISK_SEGMENTS = 128


def _disk() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mitsuba's disk: radius 1 in the xy plane facing +z, as a fan of
    :data:`DISK_SEGMENTS` triangles (area π·(1 − 4·10⁻⁴))."""
    phi = np.linspace(0.0, 2.0 * np.pi, DISK_SEGMENTS, endpoint=False)
    ring = np.stack([np.cos(phi), np.sin(phi), np.zeros_like(phi)], axis=1)
    verts = np.concatenate([np.zeros((1, 3)), ring])
    i = np.arange(DISK_SEGMENTS)
    faces = np.stack([np.zeros_like(i), 1 + i, 1 + (i + 1) % DISK_SEGMENTS], axis=1)
    return verts, faces, np.tile([0.0, 0.0, 1.0], (len(verts), 1))


def sphere() -> Built:
    """The unit sphere as an icosphere (4 subdivisions), normals its positions."""
    import trimesh

    ico = trimesh.creation.icosphere(subdivisions=4)
    n = np.asarray(ico.vertices, np.float64)
    return n, np.asarray(ico.faces, np.int64), n, None


BUILT_INS: dict[str, Callable[[], Built]] = {
    "rectangle": rectangle,
    "cube": lambda: (*_cube(), None),
    "disk": lambda: (*_disk(), None),
    "sphere": sphere,
}


def check_matrix(t: Translator, el: Element, m: np.ndarray) -> None:
    """A shape's placement checked as the core checks a ``matrix`` transform, so that the
    error names the Mitsuba element."""
    bad = first_bad_placement(m[None])
    if bad is not None:
        raise t.error(el, f"the transform {bad[1]}")


def check_group(t: Translator, group: Element) -> None:
    """A ``<shapegroup>`` holds shapes only: no instances (Mitsuba has no nested
    instancing; one of its own group would recurse) and no other shapegroup."""
    if "id" not in group.attrs:
        raise t.error(group, "a shapegroup needs an `id` for instances to refer to")
    for c in group.children:
        if c.tag == "shapegroup":
            raise t.error(c, "shapegroups cannot be nested")
        if c.tag != "shape":
            raise t.error(c, "a shapegroup holds shapes only")
        if c.attrs.get("type") == "instance":
            refs = [r.attrs.get("id") for r in c.children if r.tag == "ref"]
            if group.attrs["id"] in refs:
                raise t.error(c, "an instance of its own shapegroup (recursive)")
            raise t.error(c, "a shapegroup cannot hold instances (nested instancing)")


def instance(t: Translator, el: Element) -> None:
    """``<shape type="instance">``: the shapes of the ``<shapegroup>`` it refers to, each
    placed by the instance's ``to_world`` after its own."""
    props = t.props(el)
    groups = []
    for c in el.children:
        if c.tag == "ref":
            target = t.resolve(c)
            if target.tag != "shapegroup":
                raise t.error(c, f"refers to a <{target.tag}>, not a <shapegroup>")
            groups.append(target)
        elif c.tag not in ("transform",):
            raise t.error(c, "an instance holds a <ref> to a shapegroup and `to_world`")
    if len(groups) != 1:
        raise t.error(el, "an instance refers to one <shapegroup> (<ref id=...>)")
    t.refuse_unknown(props, {"to_world"} | {r.attrs.get("name", "") for r in groups})
    xf = transform(t, props.get("to_world"))
    check_group(t, groups[0])
    for child in groups[0].children:
        shape(t, child, xf)
