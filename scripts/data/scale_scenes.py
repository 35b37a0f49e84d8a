"""Scale scenes for issue 33: a large instanced forest and a large unique-triangle terrain.

    python scripts/data/scale_scenes.py OUT_DIR [--small] [--trees N] [--variants U] [--grid G]

Writes into OUT_DIR:
- `forest.json`: a ground quad and N trees (default 2500), each an object referencing one
  of U tree meshes (default 50, `meshes/tree_K.obj`, 5,248 triangles each: a 64-segment
  trunk and a displaced geodesic crown), so ~13M triangles from U unique meshes; every
  tree that uses a mesh names the same file (the instancing key of issue 33, item 1).
- `terrain.json`: one heightfield mesh (`terrain.obj`) of 2·G² unique triangles (default
  G = 1024: 2,097,152 triangles) under a point light.
`--small` writes the test size (8 trees of 2 variants; G = 16). Deterministic (seeded).
"""

import argparse
import json
import math
import random
from pathlib import Path


def write_obj(path: Path, vertices, faces) -> None:
    with path.open("w") as f:
        f.write("".join(f"v {x:.6f} {y:.6f} {z:.6f}\n" for x, y, z in vertices))
        f.write("".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in faces))


def icosphere(subdivisions: int):
    t = (1 + 5**0.5) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t)]
    v += [(0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    v = [tuple(c / math.sqrt(sum(x * x for x in p)) for c in p) for p in v]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4)]
    f += [(11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8)]
    f += [(3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]

    def mid(cache: dict[tuple[int, int], int], a: int, b: int) -> int:
        key = (min(a, b), max(a, b))
        if key not in cache:
            p = [(x + y) / 2 for x, y in zip(v[a], v[b], strict=True)]
            n = math.sqrt(sum(x * x for x in p))
            v.append(tuple(x / n for x in p))
            cache[key] = len(v) - 1
        return cache[key]

    for _ in range(subdivisions):
        c: dict[tuple[int, int], int] = {}
        f = [
            tri
            for a, b, cc in f
            for tri in (
                (a, mid(c, a, b), mid(c, cc, a)),
                (b, mid(c, b, cc), mid(c, a, b)),
                (cc, mid(c, cc, a), mid(c, b, cc)),
                (mid(c, a, b), mid(c, b, cc), mid(c, cc, a)),
            )
        ]
    return v, f


def tree(rng: random.Random, segments: int, subdivisions: int):
    """A closed-side trunk (2·segments triangles) and a displaced crown (20·4^s)."""
    height, radius = rng.uniform(0.5, 0.8), rng.uniform(0.03, 0.05)
    verts, faces = [], []
    for i in range(segments):
        a = 2 * math.pi * i / segments
        verts += [(radius * math.cos(a), 0.0, radius * math.sin(a))]
        verts += [(radius * math.cos(a), height, radius * math.sin(a))]
    for i in range(segments):
        j = (i + 1) % segments
        faces += [(2 * i, 2 * i + 1, 2 * j), (2 * j, 2 * i + 1, 2 * j + 1)]
    sv, sf = icosphere(subdivisions)
    crown, base = rng.uniform(0.2, 0.3), len(verts)
    for x, y, z in sv:
        r = crown * (1 + 0.15 * math.sin(7 * x + rng.random()) * math.cos(5 * z))
        verts.append((r * x, height + r * y * 1.3, r * z))
    faces += [(a + base, b + base, c + base) for a, b, c in sf]
    return verts, faces


def forest(out: Path, trees: int, variants: int, small: bool) -> int:
    rng = random.Random(33)
    (out / "meshes").mkdir(parents=True, exist_ok=True)
    counts = []
    for k in range(variants):
        verts, faces = tree(rng, 8 if small else 64, 1 if small else 4)
        write_obj(out / "meshes" / f"tree_{k}.obj", verts, faces)
        counts.append(len(faces))
    side = math.ceil(math.sqrt(trees))
    extent = side * 0.6
    objects = [
        {"shape": {"type": "quad", "size": [extent, extent]}, "material": "ground"},
    ]
    total = 2
    for i in range(trees):
        k = rng.randrange(variants)
        x = (i % side - side / 2 + 0.5) * 0.6 + rng.uniform(-0.15, 0.15)
        z = (i // side - side / 2 + 0.5) * 0.6 + rng.uniform(-0.15, 0.15)
        objects.append(
            {
                "shape": {"type": "mesh", "file": f"meshes/tree_{k}.obj"},
                "transform": {"rotate": [0, rng.uniform(0, 360), 0], "translate": [x, 0, z]},
                "material": "leaves",
            }
        )
        total += counts[k]
    scene = {
        "camera": {
            "position": [0, extent * 0.3 + 1.0, extent * 0.6 + 1.0],
            "look_at": [0, 0.5, 0],
            "up": [0, 1, 0],
            "fov": 50,
            "width": 640,
            "height": 480,
        },
        "lights": [{"type": "point", "position": [0, extent + 2, 0], "intensity": [extent**2] * 3}],
        "materials": {
            "ground": {"diffuse": [0.4, 0.35, 0.3]},
            "leaves": {"diffuse": [0.2, 0.5, 0.2]},
        },
        "objects": objects,
    }
    (out / "forest.json").write_text(json.dumps(scene, indent=1))
    return total


def terrain(out: Path, grid: int) -> int:
    def h(x: float, z: float) -> float:
        return 0.15 * math.sin(3.1 * x) * math.cos(2.3 * z) + 0.05 * math.sin(11 * x + 7 * z)

    n = grid + 1
    verts = [(2 * i / grid - 1, 0.0, 2 * j / grid - 1) for j in range(n) for i in range(n)]
    verts = [(x, h(x, z), z) for x, _, z in verts]
    faces = []
    for j in range(grid):
        for i in range(grid):
            a = j * n + i
            faces += [(a, a + n, a + 1), (a + 1, a + n, a + n + 1)]
    write_obj(out / "terrain.obj", verts, faces)
    scene = {
        "camera": {
            "position": [0, 1.2, 2.2],
            "look_at": [0, 0, 0],
            "up": [0, 1, 0],
            "fov": 45,
            "width": 640,
            "height": 480,
        },
        "lights": [{"type": "point", "position": [0.3, 1.5, 0.4], "intensity": [3, 3, 3]}],
        "materials": {"ground": {"diffuse": [0.5, 0.45, 0.4]}},
        "objects": [{"shape": {"type": "mesh", "file": "terrain.obj"}, "material": "ground"}],
    }
    (out / "terrain.json").write_text(json.dumps(scene, indent=1))
    return len(faces)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("out", type=Path)
    p.add_argument("--small", action="store_true", help="the test size")
    p.add_argument("--trees", type=int)
    p.add_argument("--variants", type=int)
    p.add_argument("--grid", type=int)
    a = p.parse_args()
    a.out.mkdir(parents=True, exist_ok=True)
    trees = a.trees or (8 if a.small else 2500)
    variants = a.variants or (2 if a.small else 50)
    grid = a.grid or (16 if a.small else 1024)
    print(f"forest.json: {forest(a.out, trees, variants, a.small)} triangles, {variants} meshes")
    print(f"terrain.json: {terrain(a.out, grid)} unique triangles")


if __name__ == "__main__":
    main()
