"""The glTF corpus of ``tests/scenes/gltf/`` and its Blender Cycles references.

Writes each asset (``tests/gltf_assets.py``: gi's own procedural models, no third-party
files), a gi scene per asset that names it with a camera, a sun and a constant sky
(``NAME.json``), and, with ``--cycles``, Cycles' image of the same scene
(``NAME.cycles.exr``, 64×64, 1024 samples, box pixel filter, linear): the glTF imported
by Blender's own importer (``bpy`` from PyPI, 4.2 LTS), the camera, sun (strength =
irradiance, W/m²) and world colour (radiance) converted from gi's y-up frame to Blender's
z-up one ((x, y, z) → (x, −z, y)). Blender's bpy wheel has no Draco library, so the Draco
asset's reference is Cycles' image of its uncompressed twin.

    python scripts/data/gltf_corpus.py            # assets and scenes
    python scripts/data/gltf_corpus.py --cycles   # also the references (bpy installed)
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "tests" / "scenes" / "gltf"
sys.path.insert(0, str(ROOT / "tests"))

SIZE = 64
SUN = [0.5, 0.5, 0.7071]  # towards the sun, gi's frame
SUN_IRRADIANCE = 3.0
SKY = 0.3


def corpus() -> dict[str, dict]:
    """Name -> (asset writer keywords, Blender twin to render instead, if any)."""
    return {
        "bumps": {"kind": "bumps"},
        "bumps_mikktspace": {"kind": "bumps", "tangents": "none"},
        "bumps_mirrored": {"kind": "bumps", "mirror_u": True},
        "bumps_quantized": {"kind": "bumps", "quantized": True},
        "texture_transform": {"kind": "textured"},
        "sphere": {"kind": "sphere", "compressed": False},
        "sphere_draco": {"kind": "sphere", "compressed": True, "cycles_twin": "sphere"},
        "lit_room": {"kind": "lights"},
    }


def write_assets() -> None:
    from gltf_assets import draco_sphere, lit_room, normal_mapped_quad, textured_quad

    OUT.mkdir(parents=True, exist_ok=True)
    for name, spec in corpus().items():
        glb = OUT / f"{name}.glb"
        kw = {k: v for k, v in spec.items() if k not in ("kind", "cycles_twin")}
        if spec["kind"] == "bumps":
            normal_mapped_quad(glb, **kw)
        elif spec["kind"] == "textured":
            transform = {"offset": [0.25, -0.1], "rotation": 0.4, "scale": [2.0, 1.5]}
            textured_quad(glb, transform=transform)
        elif spec["kind"] == "lights":
            lit_room(glb)
        else:
            draco_sphere(glb, **kw)
        if spec["kind"] == "lights":
            # The file's own lights only: no sun, no sky.
            scene = {
                "camera": {
                    "position": [0, 2.5, 4],
                    "look_at": [0, 0.4, 0],
                    "fov": 45,
                    "width": SIZE,
                    "height": SIZE,
                },
                "objects": [{"shape": {"type": "mesh", "file": glb.name}}],
            }
            (OUT / f"{name}.json").write_text(json.dumps(scene, indent=1) + "\n")
            continue
        sphere = spec["kind"] == "sphere"
        n = math.sqrt(sum(x * x for x in SUN))
        scene = {
            "camera": {
                "position": [0, 0, 4.5 if sphere else 3],
                "look_at": [0, 0, 0],
                "fov": 2 * math.degrees(math.atan(1 / 3)) * (1.0 if not sphere else 1.2),
                "width": SIZE,
                "height": SIZE,
            },
            "lights": [
                {
                    "type": "directional",
                    "direction": [-x / n for x in SUN],
                    "irradiance": [SUN_IRRADIANCE] * 3,
                }
            ],
            "environment": {"radiance": [SKY] * 3},
            "objects": [{"shape": {"type": "mesh", "file": glb.name}}],
        }
        (OUT / f"{name}.json").write_text(json.dumps(scene, indent=1) + "\n")


def to_blender(v: list[float]):
    from mathutils import Vector

    return Vector((v[0], -v[2], v[1]))


def world_of(env: dict):
    """Blender's world for gi's ``environment``: a constant colour, or an equirectangular
    image (relative to ``OUT``) read texel by texel (closest, as gi reads it)."""
    import bpy

    world = bpy.data.worlds.new("world")
    world.use_nodes = True
    bg = world.node_tree.nodes["Background"]
    if "file" in env:
        tex = world.node_tree.nodes.new("ShaderNodeTexEnvironment")
        tex.image = bpy.data.images.load(str(OUT / env["file"]))
        tex.image.colorspace_settings.name = "Linear Rec.709"
        tex.interpolation = "Closest"
        world.node_tree.links.new(tex.outputs["Color"], bg.inputs["Color"])
    else:
        sky = env.get("radiance", [0.0, 0.0, 0.0])
        bg.inputs["Color"].default_value = (*sky, 1.0)
    bg.inputs["Strength"].default_value = float(env.get("intensity", 1.0))
    return world


def render_cycles(
    name: str,
    scene: dict,
    glb: Path,
    samples: int,
    closest_texels: bool = False,
    single_scatter: bool = False,
) -> None:
    """Cycles' image of ``scene`` with the asset ``glb`` as ``OUT/NAME.cycles.exr``;
    ``closest_texels``: the material textures read texel by texel (Cycles otherwise
    interpolates 8-bit sRGB texels before decoding them, darker than gi's decoded texels
    where a texture has sharp contrasts, e.g. thin emissive lines); ``single_scatter``: the
    Principled BSDFs with single-scattering GGX (gi's model) instead of Multiscatter GGX."""
    import bpy

    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=str(glb))
    for mat in bpy.data.materials:
        for node in mat.node_tree.nodes if mat.use_nodes else []:
            if node.type == "TEX_IMAGE" and closest_texels:
                node.interpolation = "Closest"
            if node.type == "BSDF_PRINCIPLED" and single_scatter:
                node.distribution = "GGX"
    s = bpy.context.scene
    cam = scene["camera"]
    data = bpy.data.cameras.new("camera")
    data.sensor_fit = "VERTICAL"
    data.angle = math.radians(cam["fov"])
    obj = bpy.data.objects.new("camera", data)
    s.collection.objects.link(obj)
    obj.location = to_blender(cam["position"])
    look = to_blender(cam["look_at"]) - obj.location
    obj.rotation_euler = look.to_track_quat("-Z", "Y").to_euler()
    s.camera = obj
    for light in scene.get("lights", []):
        sun = bpy.data.lights.new("sun", "SUN")
        sun.energy = light["irradiance"][0]
        sun.angle = 0.0
        lo = bpy.data.objects.new("sun", sun)
        s.collection.objects.link(lo)
        lo.rotation_euler = to_blender(light["direction"]).to_track_quat("-Z", "Y").to_euler()
    s.world = world_of(scene.get("environment", {}))
    s.render.engine = "CYCLES"
    s.cycles.device = "CPU"
    s.cycles.samples = samples
    s.cycles.use_denoising = False
    s.cycles.pixel_filter_type = "BOX"
    s.cycles.filter_width = 1.0
    s.cycles.max_bounces = 32
    s.render.resolution_x, s.render.resolution_y = cam["width"], cam["height"]
    s.render.resolution_percentage = 100
    s.view_settings.view_transform = "Standard"
    s.render.image_settings.file_format = "OPEN_EXR"
    s.render.image_settings.color_depth = "16"
    s.render.image_settings.exr_codec = "ZIP"
    s.render.filepath = str(OUT / f"{name}.cycles.exr")
    bpy.ops.render.render(write_still=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cycles", action="store_true", help="also render Cycles' references")
    ap.add_argument("--samples", type=int, default=1024)
    args = ap.parse_args()
    write_assets()
    if args.cycles:
        for name, spec in corpus().items():
            scene = json.loads((OUT / f"{name}.json").read_text())
            glb = OUT / f"{spec.get('cycles_twin', name)}.glb"
            render_cycles(name, scene, glb, args.samples)


if __name__ == "__main__":
    main()
