"""Load and render time of imported scenes whose meshes are used many times: a glTF file of
one sphere mesh on N nodes (loaded as a scene: N instances of one mesh; named as a mesh file
by a JSON scene: flattened into N copies) and a Mitsuba scene of one PLY sphere used by N
shapes (instances; and the same scene with the old importer's behaviour emulated by one PLY
file per shape, baked into world space); and a glTF node placing the sphere M times by
``EXT_mesh_gpu_instancing``. Prints a Markdown table.

    .venv/bin/python scripts/bench/bench_import_instances.py [--copies 100] [--subdivisions 5]
        [--gpu-instances 100000]
"""

from __future__ import annotations

import argparse
import base64
import json
import tempfile
import time
from pathlib import Path

import numpy as np
import trimesh

import gi


def sphere(subdivisions: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    ico = trimesh.creation.icosphere(subdivisions=subdivisions, radius=0.4)
    v = np.asarray(ico.vertices)
    return v, np.asarray(ico.faces), v / np.linalg.norm(v, axis=1, keepdims=True)


def grid(copies: int) -> list[np.ndarray]:
    side = int(np.ceil(np.sqrt(copies)))
    return [np.array([(i % side) - side / 2, 0.4, -(i // side)], float) for i in range(copies)]


LIGHT_Y = 6.0


def gltf(dir: Path, v, f, n, copies: int, gpu_instances: int = 0) -> Path:
    blob = b""
    views, accessors = [], []
    arrays = [(v, "VEC3", 5126), (n, "VEC3", 5126), (f.ravel(), "SCALAR", 5125)]
    if gpu_instances:
        arrays.append((np.array(grid(gpu_instances)), "VEC3", 5126))
    for arr, kind, ctype in arrays:
        data = np.ascontiguousarray(arr, np.float32 if ctype == 5126 else np.uint32).tobytes()
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(data)})
        blob += data
        acc = {"bufferView": len(views) - 1, "componentType": ctype, "type": kind}
        acc["count"] = len(arr)
        accessors.append(acc)
    nodes = [{"mesh": 0, "translation": t.tolist()} for t in grid(copies)]
    if gpu_instances:
        ext = {"EXT_mesh_gpu_instancing": {"attributes": {"TRANSLATION": 3}}}
        nodes = [{"mesh": 0, "extensions": ext}]
    nodes.append(
        {"extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [0, LIGHT_Y, 0]}
    )
    uri = "data:application/octet-stream;base64," + base64.b64encode(blob).decode()
    doc = {
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": len(blob), "uri": uri}],
        "bufferViews": views,
        "accessors": accessors,
        "materials": [{"name": "m", "pbrMetallicRoughness": {"metallicFactor": 0.0}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2,
                                    "material": 0}]}],
        "nodes": nodes,
        "scenes": [{"nodes": list(range(len(nodes)))}],
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point",
                                                           "intensity": 683 * 40}]}},
    }  # fmt: skip
    path = dir / ("gpu.gltf" if gpu_instances else "spheres.gltf")
    path.write_text(json.dumps(doc))
    return path


def ply(path: Path, v, f, n) -> None:
    head = (
        f"ply\nformat binary_little_endian 1.0\nelement vertex {len(v)}\n"
        + "".join(f"property float {a}\n" for a in ("x", "y", "z", "nx", "ny", "nz"))
        + f"element face {len(f)}\nproperty list uchar int vertex_indices\nend_header\n"
    )
    verts = np.concatenate([v, n], axis=1).astype("<f4").tobytes()
    faces = np.zeros(len(f), dtype=[("n", "u1"), ("i", "<i4", 3)])
    faces["n"], faces["i"] = 3, f
    path.write_bytes(head.encode() + verts + faces.tobytes())


def mitsuba(dir: Path, v, f, n, copies: int, baked: bool) -> Path:
    shapes = []
    for i, t in enumerate(grid(copies)):
        if baked:
            ply(dir / f"baked{i}.ply", v + t, f, n)
            shapes.append(
                f'<shape type="ply"><string name="filename" value="baked{i}.ply"/></shape>'
            )
        else:
            shapes.append(
                '<shape type="ply"><string name="filename" value="sphere.ply"/>'
                f'<transform name="to_world"><translate value="{t[0]}, {t[1]}, {t[2]}"/>'
                "</transform></shape>"
            )
    if not baked:
        ply(dir / "sphere.ply", v, f, n)
    path = dir / ("baked.xml" if baked else "instanced.xml")
    path.write_text(
        '<scene version="3.0.0"><sensor type="perspective"><float name="fov" value="60"/>'
        '<transform name="to_world"><lookat origin="0, 8, 6" target="0, 0, -4" up="0, 1, 0"/>'
        '</transform></sensor><emitter type="point">'
        f'<point name="position" value="0, {LIGHT_Y}, 0"/>'
        '<rgb name="intensity" value="40"/></emitter>' + "".join(shapes) + "</scene>"
    )
    return path


def timed(path: Path) -> tuple[float, float, gi.Scene]:
    t = time.perf_counter()
    scene = gi.load_scene(path)
    load = time.perf_counter() - t
    gi.render(scene, "path", width=64, height=64, spp=4, seed=1)
    return load, time.perf_counter() - t, scene


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--copies", type=int, default=100)
    p.add_argument("--subdivisions", type=int, default=5)
    p.add_argument("--gpu-instances", type=int, default=100_000)
    args = p.parse_args()
    v, f, n = sphere(args.subdivisions)
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        g = gltf(d, v, f, n, args.copies)
        (d / "flat.json").write_text(
            json.dumps(
                {
                    "camera": {"position": [0, 8, 6], "look_at": [0, 0, -4], "fov": 60},
                    "objects": [{"shape": {"type": "mesh", "file": g.name}}],
                }
            )
        )
        rows = [
            ("glTF as a scene (instances)", g),
            ("glTF as a JSON mesh file (flattened)", d / "flat.json"),
            (
                "Mitsuba, one PLY on every shape (instances)",
                mitsuba(d, v, f, n, args.copies, False),
            ),
            (
                "Mitsuba, one baked PLY per shape (flattened)",
                mitsuba(d, v, f, n, args.copies, True),
            ),
            (
                f"glTF EXT_mesh_gpu_instancing, {args.gpu_instances:,} placements",
                gltf(d, v, f, n, 0, args.gpu_instances),
            ),
        ]
        print(f"{args.copies} spheres of {len(f)} triangles; `path` 64×64, 4 spp\n")
        print("| scene | unique triangles | placed triangles | load | load + render |")
        print("|---|---|---|---|---|")
        for name, path in rows:
            load, total, s = timed(path)
            print(
                f"| {name} | {s.unique_triangle_count:,} | {s.triangle_count:,} | "
                f"{load:.2f} s | {total:.2f} s |"
            )


if __name__ == "__main__":
    main()
