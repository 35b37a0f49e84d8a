"""scripts/scale_scenes.py at its test size: both scenes load with the triangle counts the
script reports, the forest's trees share their mesh files, and both render finite images."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np

import gi

SCRIPT = Path(__file__).resolve().parent.parent / "scripts" / "scale_scenes.py"


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
