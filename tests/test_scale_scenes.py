"""scripts/data/scale_scenes.py at its test size: both scenes load with the triangle counts the
script reports, the forest's trees share their mesh files, and both render finite images; a
scene of billions of instanced triangles loads, and its world-space copy is refused by estimate."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import gi

SCRIPT = Path(__file__).resolve().parent.parent / "scripts" / "data" / "scale_scenes.py"


def test_small_scale_scenes_load_and_render(tmp_path):
    out = subprocess.run(
        [sys.executable, str(SCRIPT), str(tmp_path), "--small"],
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    lines = dict(line.split(": ", 1) for line in out.strip().splitlines())
    forest_tris = int(lines["forest.json"].split()[0])
    terrain_tris = int(lines["terrain.json"].split()[0])
    # 8 trees of 2 variants: trunk 16 + crown 80 triangles each, plus the ground quad.
    assert forest_tris == 8 * 96 + 2
    assert terrain_tris == 2 * 16 * 16
    desc = json.loads((tmp_path / "forest.json").read_text())
    files = [o["shape"]["file"] for o in desc["objects"] if o["shape"]["type"] == "mesh"]
    assert len(files) == 8 and len(set(files)) == 2
    for name, tris in [("forest.json", forest_tris), ("terrain.json", terrain_tris)]:
        scene = gi.load_scene(str(tmp_path / name))
        assert scene.triangle_count == tris
        # The trees that name one file are instances of one mesh: the ground and 2 trees.
        unique = 2 + 2 * 96 if name == "forest.json" else tris
        assert scene.unique_triangle_count == unique
        r = gi.render(scene, "path", spp=1, size=(16, 12))
        assert np.isfinite(r.radiance).all() and r.radiance.mean() > 0


def test_world_space_copy_of_billions_of_instances_is_refused():
    """200,000 instances of one 20,480-triangle sphere (4.1e9 placed triangles) load as one
    mesh, and the GPU methods draw them instanced; their world-space copy
    (``Scene.mesh_arrays``, ~190 GB) is refused by its estimate with a typed error before
    anything is allocated."""
    desc = json.loads(gi.builtin_json("cornell"))
    desc["objects"].append(
        {
            "name": "big",
            "shape": {"type": "sphere", "radius": 0.004, "subdivisions": 5},
            "transform": {"translate": [0, 0.01, 0]},
            "material": "white",
        }
    )
    side = 448
    desc["objects"] += [
        {
            "shape": {"type": "instance", "object": "big"},
            "transform": {
                "translate": [-0.9 + 1.8 * (i % side) / side, 0.01, -0.9 + 1.8 * (i // side) / side]
            },
        }
        for i in range(200_000)
    ]
    scene = gi.Scene.from_json(json.dumps(desc), "many")
    assert scene.unique_triangle_count < 30_000
    with pytest.raises(gi.OutOfMemoryError, match="world-space triangles"):
        scene.mesh_arrays()
