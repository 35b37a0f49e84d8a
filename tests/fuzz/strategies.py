"""Hypothesis strategies for hostile gi inputs: scene descriptions, mesh files (OBJ, PLY, STL,
glTF/GLB) and render settings.

Values are mostly plausible with a share of extremes (zeros, denormals, 1e38, NaN, huge and
negative integers, wrong types), and structures are sometimes broken (unknown fields,
missing sections, deep nesting, truncated or bit-flipped files). Valid settings are kept
cheap (tiny images, few photons) so that a case that renders finishes in well under a
second; invalid ones may be absurd.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
from hypothesis import strategies as st

EXTREME_FLOATS = [
    0.0,
    -0.0,
    1e-45,
    1e-38,
    1e-12,
    1e-6,
    1e5,
    1e6,
    1e15,
    1e38,
    3.4e38,
    -1e38,
    math.inf,
    -math.inf,
    math.nan,
]
EXTREME_INTS = [-(2**64), -1, 0, 2**31, 2**32, 2**63, 2**64, 10**30]


@st.composite
def number(draw: st.DrawFn, lo: float = -10.0, hi: float = 10.0, bad: float = 0.0) -> float:
    """In [lo, hi], except with probability `bad`: an extreme or any float at all."""
    if bad > 0.0 and draw(st.floats(0.0, 1.0)) < bad:
        return draw(
            st.one_of(
                st.sampled_from(EXTREME_FLOATS), st.floats(allow_nan=True, allow_infinity=True)
            )
        )
    return draw(st.floats(lo, hi))


def vec3(lo: float = -10.0, hi: float = 10.0, bad: float = 0.0) -> st.SearchStrategy[list[float]]:
    return st.lists(number(lo, hi, bad), min_size=3, max_size=3)


def camera(bad: float) -> st.SearchStrategy[dict[str, Any]]:
    return st.fixed_dictionaries(
        {"position": vec3(-6.0, 6.0, bad), "look_at": vec3(-1.0, 1.0, bad)},
        optional={
            "up": vec3(-1.0, 1.0, bad),
            "fov": number(10.0, 120.0, bad),
            "width": st.one_of(st.integers(1, 16), st.sampled_from(EXTREME_INTS))
            if bad
            else st.integers(1, 16),
            "height": st.integers(1, 16),
        },
    )


def light(bad: float) -> st.SearchStrategy[dict[str, Any]]:
    intensity = st.lists(number(0.0, 50.0, bad), min_size=3, max_size=3)
    point = st.fixed_dictionaries(
        {"type": st.just("point"), "position": vec3(-3.0, 3.0, bad), "intensity": intensity}
    )
    spot = st.fixed_dictionaries(
        {
            "type": st.just("spot"),
            "position": vec3(-3.0, 3.0, bad),
            "direction": vec3(-1.0, 1.0, bad),
            "intensity": intensity,
        },
        optional={"inner_angle": number(0.0, 40.0, bad), "outer_angle": number(41.0, 89.0, bad)},
    )
    sun = st.fixed_dictionaries(
        {
            "type": st.just("directional"),
            "direction": vec3(-1.0, 1.0, bad),
            "irradiance": intensity,
        },
        optional={"angular_diameter": number(0.0, 40.0, bad)},
    )
    return st.one_of(point, spot, sun)


@st.composite
def material(draw: st.DrawFn, bad: float) -> dict[str, Any]:
    """Energy-conserving channels unless `bad` says otherwise."""
    out: dict[str, Any] = {}
    t = draw(st.sampled_from([0.0, 0.0, 0.0, 0.5, 1.0]))
    if t > 0.0:
        out["transmission"] = [t] * 3
        out["ior"] = draw(number(1.0, 3.0, bad))
    out["diffuse"] = draw(st.lists(number(0.0, 1.0 - t, bad), min_size=3, max_size=3))
    if draw(st.booleans()):
        out["specular"] = draw(st.lists(number(0.0, 1.0, bad), min_size=3, max_size=3))
        out["roughness"] = draw(number(0.0, 1.0, bad))
        out["fresnel"] = draw(st.booleans())
    if draw(st.integers(0, 3)) == 0:
        # An area light: any shape emits, degenerate ones (size 0) included.
        out["emission"] = draw(st.lists(number(0.0, 20.0, bad), min_size=3, max_size=3))
        out["two_sided"] = draw(st.booleans())
    return out


def transform(bad: float = 0.2) -> st.SearchStrategy[dict[str, Any]]:
    trs = st.fixed_dictionaries(
        {},
        optional={
            "translate": vec3(-2.0, 2.0, bad),
            "rotate": vec3(-360.0, 360.0, bad),
            "scale": st.one_of(number(0.05, 3.0, bad), vec3(0.05, 3.0, bad)),
        },
    )
    return st.one_of(trs, trs, trs, matrix_transform(bad))


@st.composite
def matrix_transform(draw: st.DrawFn, bad: float) -> dict[str, Any]:
    """A general affine ``matrix`` transform: 3 rows of 4 (sometimes a 4th row), a share
    of them singular (two equal columns), mirrored, non-finite or misshapen, or given with
    translate/rotate/scale (which it excludes)."""
    rows = [draw(st.lists(number(-2.0, 2.0, bad), min_size=4, max_size=4)) for _ in range(3)]
    kind = draw(st.sampled_from(["plain"] * 6 + ["singular", "fourth", "misshapen", "both"]))
    if kind == "singular":
        for r in rows:
            r[1] = r[0]
    elif kind == "fourth":
        rows.append(draw(st.sampled_from([[0, 0, 0, 1], [0, 0, 0, 1], [0, 0, 1, 1], [0, 0, 0]])))
    elif kind == "misshapen":
        rows = draw(st.sampled_from([rows[:2], [r[:3] for r in rows], [], [[1.0] * 4] * 5]))
    out: dict[str, Any] = {"matrix": rows}
    if kind == "both":
        out["translate"] = draw(vec3(-2.0, 2.0, bad))
    return out


def shape(bad: float) -> st.SearchStrategy[dict[str, Any]]:
    size = number(0.05, 3.0, bad)
    segments = (
        st.one_of(st.integers(3, 48), st.sampled_from([0, 4097, 2**40]))
        if bad
        else st.integers(3, 48)
    )
    subdivisions = (
        st.one_of(st.integers(0, 3), st.sampled_from([7, 8, 2**32])) if bad else st.integers(0, 3)
    )
    return st.one_of(
        st.fixed_dictionaries(
            {"type": st.just("quad"), "size": st.lists(size, min_size=2, max_size=2)}
        ),
        st.fixed_dictionaries(
            {"type": st.just("box"), "size": st.lists(size, min_size=3, max_size=3)}
        ),
        st.fixed_dictionaries(
            {"type": st.just("sphere"), "radius": size},
            optional={"subdivisions": subdivisions},
        ),
        st.fixed_dictionaries(
            {"type": st.just("cylinder"), "radius": size, "height": size},
            optional={"segments": segments, "caps": st.booleans()},
        ),
        st.fixed_dictionaries(
            {
                "type": st.just("ring"),
                "inner_radius": number(0.05, 1.0, bad),
                "outer_radius": number(1.05, 3.0, bad),
                "height": size,
            },
            optional={"segments": segments},
        ),
    )


#: Per-number probability of an extreme value: half the scenes are plausible throughout.
BAD_RATES = [0.0, 0.0, 0.0, 0.0, 0.01, 0.03, 0.1, 0.3]


@st.composite
def scene_desc(draw: st.DrawFn) -> dict[str, Any]:
    """A scene description dict; materials referenced by objects mostly exist."""
    bad = draw(st.sampled_from(BAD_RATES))
    materials = draw(
        st.dictionaries(st.sampled_from(["a", "b", "c"]), material(bad), min_size=1, max_size=3)
    )
    names = [*materials, "missing"] if bad else list(materials)
    objects = draw(
        st.lists(
            st.fixed_dictionaries(
                {"shape": shape(bad), "material": st.sampled_from(names)},
                optional={"transform": transform(bad)},
            ),
            max_size=4,
        )
    )
    # Instances: objects named o0, o1, ... and some shapes replaced by a reference to one of
    # those names (or a missing one): chains, self-references and cycles included.
    for i, obj in enumerate(objects):
        if draw(st.integers(0, 2)) == 0:
            obj["name"] = f"o{i}"
        if draw(st.integers(0, 3)) == 0:
            target = draw(st.sampled_from([f"o{j}" for j in range(len(objects))] + ["nowhere"]))
            obj["shape"] = {"type": "instance", "object": target}
    desc = {
        "camera": draw(camera(bad)),
        "lights": draw(st.lists(light(bad), max_size=3)),
        "materials": materials,
        "objects": objects,
    }
    if draw(st.integers(0, 4)) == 0:
        desc["environment"] = {"radiance": draw(vec3(0.0, 2.0, bad))}
    return desc


@st.composite
def scene_text(draw: st.DrawFn) -> str:
    """JSON text of a scene, sometimes broken: an unknown field, a wrong type, a cut-off or
    deeply nested document."""
    desc = draw(scene_desc())
    text = json.dumps(desc)  # NaN/Infinity are written as such: not JSON, a SceneError
    mutation = draw(
        st.sampled_from(["none"] * 12 + ["unknown", "wrong_type", "truncate", "nest", "garbage"])
    )
    if mutation == "unknown":
        desc["camera"]["colour"] = 1
        text = json.dumps(desc)
    elif mutation == "wrong_type":
        desc[draw(st.sampled_from(["camera", "lights", "materials", "objects"]))] = "x"
        text = json.dumps(desc)
    elif mutation == "truncate":
        text = text[: draw(st.integers(0, max(len(text) - 1, 0)))]
    elif mutation == "nest":
        depth = draw(st.sampled_from([50, 200, 5000, 100_000]))
        text = text[:-1] + ', "extra": ' + "[" * depth + "]" * depth + "}"
    elif mutation == "garbage":
        text = draw(st.text(max_size=64))
    return text


# Meshes ----------------------------------------------------------------------------------


@st.composite
def mesh_arrays(draw: st.DrawFn) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (N, 3) float64 and faces (M, 3) int64, sometimes with extreme coordinates
    or indices out of range."""
    n = draw(st.integers(3, 40))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    v = rng.uniform(-1.0, 1.0, (n, 3))
    if draw(st.integers(0, 3)) == 0:
        v[draw(st.integers(0, n - 1)), draw(st.integers(0, 2))] = draw(
            st.sampled_from(EXTREME_FLOATS)
        )
    m = draw(st.integers(1, 60))
    f = rng.integers(0, n, (m, 3))
    if draw(st.integers(0, 5)) == 0:
        f[draw(st.integers(0, m - 1)), 0] = draw(st.sampled_from([n, n + 7, 2**31 - 1]))
    return v, f


MESH_FORMATS = ["obj", "ply", "ply_ascii", "stl", "stl_ascii", "glb", "stl_solid_header"]


@st.composite
def mesh_file(draw: st.DrawFn, directory: Path) -> Path:
    """Writes a mesh file in one of the formats, sometimes corrupted; returns its path."""
    import trimesh

    v, f = draw(mesh_arrays())
    fmt = draw(st.sampled_from(MESH_FORMATS))
    data: bytes
    if fmt == "obj":
        # Written by hand: trimesh's exporter would drop out-of-range faces.
        lines = [f"v {a!r} {b!r} {c!r}" for a, b, c in v.tolist()]
        lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in f.tolist()]
        data, suffix = ("\n".join(lines) + "\n").encode(), ".obj"
    elif fmt == "glb":
        scene = trimesh.Scene()
        mesh = trimesh.Trimesh(np.nan_to_num(v), f % len(v), process=False)
        scale = draw(st.sampled_from([1.0, 1.0, 0.0, 1e-20, 1e20, 1e38]))
        scene.add_geometry(mesh, geom_name="m", transform=np.diag([scale, 1.0, 1.0, 1.0]))
        # More nodes sharing the mesh (instances when the file is loaded as a scene), some
        # mirrored or sheared.
        for i in range(draw(st.integers(0, 3))):
            m = np.eye(4)
            m[0, :] = [draw(st.sampled_from([1.0, -1.0, 0.5, 0.0])), draw(number(-1, 1)), 0, i]
            scene.graph.update(frame_to=f"copy{i}", frame_from=scene.graph.base_frame,
                               matrix=m, geometry="m")  # fmt: skip
        data, suffix = scene.export(file_type="glb"), ".glb"
    else:
        mesh = trimesh.Trimesh(v, f % len(v), process=False)
        ftype = {"ply_ascii": "ply", "stl_ascii": "stl_ascii", "stl_solid_header": "stl"}.get(
            fmt, fmt
        )
        kwargs = {"encoding": "ascii"} if fmt == "ply_ascii" else {}
        out = mesh.export(file_type=ftype, **kwargs)
        data = out if isinstance(out, bytes) else out.encode()
        if fmt == "stl_solid_header":
            data = b"solid gi".ljust(80, b" ") + data[80:]
        suffix = ".ply" if fmt.startswith("ply") else ".stl"
        if fmt.startswith("ply") and draw(st.booleans()):
            # A face index out of range, as a broken exporter might write it.
            data = data.replace(b"3 0 ", b"3 999999 ", 1)
    corruption = draw(st.sampled_from(["none"] * 5 + ["truncate", "flip", "empty"]))
    if corruption == "truncate" and data:
        data = data[: draw(st.integers(0, len(data) - 1))]
    elif corruption == "flip" and data:
        b = bytearray(data)
        for _ in range(draw(st.integers(1, 8))):
            b[draw(st.integers(0, len(b) - 1))] ^= 1 << draw(st.integers(0, 7))
        data = bytes(b)
    elif corruption == "empty":
        data = b""
    path = directory / f"mesh{suffix}"
    path.write_bytes(data)
    return path


# Settings --------------------------------------------------------------------------------

METHODS = ["path", "photon", "gather", "direct", "ispm"]
HOSTILE = [-1, 2**32, 2**64, 10**30, math.nan, math.inf, -math.inf, "8", None, [1], True]


@st.composite
def cheap_or_hostile(draw: st.DrawFn, cheap: st.SearchStrategy[Any], bad: float) -> Any:
    if bad > 0.0 and draw(st.floats(0.0, 1.0)) < bad:
        return draw(st.sampled_from(HOSTILE))
    return draw(cheap)


@st.composite
def render_settings(draw: st.DrawFn) -> dict[str, Any]:
    """Keyword arguments of `gi.render` besides the scene: cheap valid values or absurd
    ones (which must raise `gi.SettingError`)."""
    bad = draw(st.sampled_from([0.0, 0.0, 0.0, 0.03, 0.1, 0.3]))

    def pick(cheap: st.SearchStrategy[Any]) -> st.SearchStrategy[Any]:
        return cheap_or_hostile(cheap, bad)

    return draw(
        st.fixed_dictionaries(
            {
                "method": pick(st.sampled_from(METHODS)),
                "size": st.one_of(
                    *[st.tuples(st.integers(1, 12), st.integers(1, 12))] * 4,
                    st.sampled_from([(0, 4), (-1, 4), (2**40, 2), (4,), "8x8"]),
                )
                if bad
                else st.tuples(st.integers(1, 12), st.integers(1, 12)),
                # Always given: the defaults (64 spp, 200,000 photons) are not cheap.
                "spp": pick(st.integers(1, 4)),
                "photons": pick(st.integers(1, 5000)),
                "shadow_map_size": pick(st.integers(16, 128)),
            },
            optional={
                "seed": pick(st.integers(0, 2**64 - 1)),
                "max_depth": pick(st.integers(1, 1024)),
                "light_paths": pick(st.integers(0, 2000)),
                "k": pick(st.integers(1, 200)),
                "max_radius": pick(st.floats(1e-3, 10.0)),
                "kernel": pick(st.sampled_from(["box", "cone", "epanechnikov"])),
                "smoothing": pick(st.floats(0.01, 100.0)),
                "leaf_size": pick(st.integers(1, 4096)),
                "final_gather": pick(st.booleans()),
                "kernel_scale": pick(st.floats(0.01, 10.0)),
                "subsample": pick(st.integers(1, 8)),
                "footprint_volumes": pick(st.booleans()),
                "boundary_compensation": pick(st.booleans()),
                "edge_supersampling": pick(st.booleans()),
                "area_samples": pick(st.integers(1, 8)),
                "sky_samples": pick(st.integers(1, 8)),
                "volume_shape": pick(st.sampled_from(["auto", "quad", "icosahedron"])),
            },
        )
    )
