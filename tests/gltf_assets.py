"""Small glTF assets written here for the tests (and by ``scripts/data/gltf_corpus.py`` for
the committed corpus): a GLB writer over numpy arrays, and a normal-mapped quad whose map
holds analytic bumps, with its tangents stored, left out, or with its UVs mirrored.

Everything is in glTF's conventions: texture coordinates with v down the image, a normal
map's +y up the image, ``TANGENT`` w such that the bitangent ``w · n × t`` points up the
image (towards −v)."""

from __future__ import annotations

import json
import struct
from pathlib import Path
from typing import Any

import numpy as np
import OpenImageIO as oiio  # noqa: N813

FLOAT, BYTE, UBYTE, SHORT, USHORT, UINT = 5126, 5120, 5121, 5122, 5123, 5125
_KIND = {1: "SCALAR", 2: "VEC2", 3: "VEC3", 4: "VEC4"}
_DTYPE = {
    FLOAT: np.float32,
    BYTE: np.int8,
    UBYTE: np.uint8,
    SHORT: np.int16,
    USHORT: np.uint16,
    UINT: np.uint32,
}


class Glb:
    """Builds one glTF document with one binary buffer; :meth:`write` saves a ``.glb``."""

    def __init__(self) -> None:
        self.blob = bytearray()
        self.doc: dict[str, Any] = {
            "asset": {"version": "2.0", "generator": "gi tests/gltf_assets.py"},
            "scene": 0,
            "scenes": [{"nodes": []}],
            "nodes": [],
            "meshes": [],
            "materials": [],
            "textures": [],
            "images": [],
            "samplers": [{"wrapS": 10497, "wrapT": 10497}],
            "accessors": [],
            "bufferViews": [],
        }

    def view(self, data: bytes) -> int:
        while len(self.blob) % 4:
            self.blob.append(0)
        self.doc["bufferViews"].append(
            {"buffer": 0, "byteOffset": len(self.blob), "byteLength": len(data)}
        )
        self.blob += data
        return len(self.doc["bufferViews"]) - 1

    def accessor(self, arr: np.ndarray, comp: int = FLOAT, normalized: bool = False) -> int:
        arr = np.asarray(arr)
        a = np.ascontiguousarray(arr.reshape(len(arr), -1), _DTYPE[comp])
        acc: dict[str, Any] = {
            "bufferView": self.view(a.tobytes()),
            "componentType": comp,
            "count": len(a),
            "type": _KIND[a.shape[1]],
        }
        if normalized:
            acc["normalized"] = True
        if a.shape[1] == 3:
            acc["min"], acc["max"] = a.min(0).tolist(), a.max(0).tolist()
        self.doc["accessors"].append(acc)
        return len(self.doc["accessors"]) - 1

    def image(self, rgba: np.ndarray, srgb: bool) -> int:
        """A PNG (8-bit; colour sRGB-encoded when ``srgb``) embedded in the buffer."""
        import tempfile

        img = np.clip(np.asarray(rgba, np.float64), 0, 1).copy()
        if srgb:
            c = img[..., :3]
            img[..., :3] = np.where(c <= 0.0031308, c * 12.92, 1.055 * c ** (1 / 2.4) - 0.055)
        h, w, c = img.shape
        with tempfile.TemporaryDirectory() as tmp:
            file = str(Path(tmp) / "i.png")
            out = oiio.ImageOutput.create(file)
            assert out.open(file, oiio.ImageSpec(w, h, c, oiio.UINT8))
            assert out.write_image(np.round(img * 255).astype(np.uint8))
            out.close()
            data = Path(file).read_bytes()
        self.doc["images"].append({"bufferView": self.view(data), "mimeType": "image/png"})
        self.doc["textures"].append({"source": len(self.doc["images"]) - 1, "sampler": 0})
        return len(self.doc["textures"]) - 1

    def mesh(self, primitives: list[dict[str, Any]], **node: Any) -> int:
        self.doc["meshes"].append({"primitives": primitives})
        self.doc["nodes"].append({"mesh": len(self.doc["meshes"]) - 1, **node})
        self.doc["scenes"][0]["nodes"].append(len(self.doc["nodes"]) - 1)
        return len(self.doc["nodes"]) - 1

    def material(self, mat: dict[str, Any]) -> int:
        self.doc["materials"].append(mat)
        return len(self.doc["materials"]) - 1

    def write(self, path: Path) -> Path:
        doc = {k: v for k, v in self.doc.items() if v != []}
        while len(self.blob) % 4:
            self.blob.append(0)
        doc["buffers"] = [{"byteLength": len(self.blob)}]
        text = json.dumps(doc).encode()
        text += b" " * (-len(text) % 4)
        body = struct.pack("<II", len(text), 0x4E4F534A) + text
        body += struct.pack("<II", len(self.blob), 0x004E4942) + bytes(self.blob)
        path.write_bytes(struct.pack("<III", 0x46546C67, 2, 12 + len(body)) + body)
        return path


def bump_normals(n: int = 64, cells: int = 4, height: float = 0.6) -> np.ndarray:
    """A tangent-space normal map (n×n, RGB in [0, 1], +x right, +y up the image) of
    ``cells``² round bumps: in each cell a spherical cap whose normal tilts away from the
    cell's centre by up to ~``height`` rad, flat between caps."""
    c = (np.arange(n) + 0.5) / n * cells
    fx = c[None, :] % 1.0 - 0.5  # right in the image
    fy = -(c[:, None] % 1.0 - 0.5)  # up in the image
    r = np.hypot(fx, fy)
    inside = r < 0.4
    tilt = np.where(inside, height * r / 0.4, 0.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        ux, uy = np.where(inside, fx / r, 0.0), np.where(inside, fy / r, 0.0)
    nx, ny = np.sin(tilt) * ux, np.sin(tilt) * uy
    nz = np.cos(tilt)
    return np.stack([nx, ny, nz], -1) * 0.5 + 0.5


def normal_mapped_quad(
    path: Path,
    tangents: str = "stored",
    mirror_u: bool = False,
    quantized: bool = False,
    emissive: float = 0.0,
    transform: dict[str, Any] | None = None,
) -> Path:
    """A 2×2 m quad in the xy plane facing +z (glTF's default view), u along +x (or −x with
    ``mirror_u``: the map mirrored, as in Khronos' NormalTangentMirrorTest), v down the
    image along −y, a white-ish diffuse material with :func:`bump_normals`. ``tangents``:
    "stored" (the right TANGENT: +x or −x and w = +1 or −1), "none" (MikkTSpace's), or
    "wrong-w" (stored with w negated: what a reader that ignores handedness gets);
    ``emissive``: a red emissive factor (an indicator light, not lighting); ``transform``:
    the normal map's ``KHR_texture_transform`` (the stored tangents stay those of the
    untransformed UVs, as an exporter writes them)."""
    g = Glb()
    pos = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], np.float32)
    nrm = np.tile([0.0, 0.0, 1.0], (4, 1))
    u = np.array([0.0, 1.0, 1.0, 0.0])
    v = np.array([1.0, 1.0, 0.0, 0.0])
    if mirror_u:
        u = 1.0 - u
    uv = np.stack([u, v], 1)
    # Tangent along +u; up the image (−v) is +y, and n × t = ±y: w = +1 unmirrored.
    t = np.array([-1.0 if mirror_u else 1.0, 0.0, 0.0])
    w = -1.0 if mirror_u else 1.0
    if tangents == "wrong-w":
        w = -w
    tan = np.tile([*t, w], (4, 1))
    idx = np.array([0, 1, 2, 0, 2, 3], np.uint16)
    if quantized:
        attrs = {
            "POSITION": g.accessor(pos.astype(np.int16), SHORT),
            "NORMAL": g.accessor(np.round(nrm * 127), BYTE, normalized=True),
            "TEXCOORD_0": g.accessor(np.round(uv * 65535), USHORT, normalized=True),
        }
        if tangents != "none":
            attrs["TANGENT"] = g.accessor(np.round(tan * 127), BYTE, normalized=True)
        g.doc["extensionsUsed"] = ["KHR_mesh_quantization"]
        g.doc["extensionsRequired"] = ["KHR_mesh_quantization"]
    else:
        attrs = {"POSITION": g.accessor(pos), "NORMAL": g.accessor(nrm)}
        attrs["TEXCOORD_0"] = g.accessor(uv)
        if tangents != "none":
            attrs["TANGENT"] = g.accessor(tan)
    normal_tex = g.image(bump_normals(), srgb=False)
    normal_info: dict[str, Any] = {"index": normal_tex}
    if transform is not None:
        normal_info["extensions"] = {"KHR_texture_transform": transform}
        g.doc.setdefault("extensionsUsed", []).append("KHR_texture_transform")
    mat = g.material(
        {
            "name": "bumps",
            "pbrMetallicRoughness": {
                "baseColorFactor": [0.8, 0.8, 0.8, 1.0],
                "metallicFactor": 0.0,
                "roughnessFactor": 1.0,
            },
            "normalTexture": normal_info,
            "emissiveFactor": [emissive, 0.0, 0.0],
        }
    )
    prim = {"attributes": attrs, "indices": g.accessor(idx, USHORT), "material": mat}
    g.mesh([prim])
    return g.write(path)


def checker(n: int = 16, cells: int = 4) -> np.ndarray:
    """An n×n RGBA checker: red where (i + j) is even, blue elsewhere; a white mark in the
    top-left texel cell so that mirrors and rotations show."""
    idx = np.arange(n) * cells // n
    even = (idx[:, None] + idx[None, :]) % 2 == 0
    rgb = np.where(even[..., None], [0.8, 0.1, 0.1], [0.1, 0.1, 0.8])
    rgb[: n // cells, : n // (2 * cells)] = 0.9
    return np.concatenate([rgb, np.ones((n, n, 1))], axis=2)


def textured_quad(
    path: Path, transform: dict[str, Any] | None = None, uv_matrix: np.ndarray | None = None
) -> Path:
    """The 2×2 quad facing +z with a :func:`checker` base colour; ``transform``: its
    ``KHR_texture_transform``; ``uv_matrix``: a 3×3 matrix applied to the stored UVs
    instead (the same picture, baked)."""
    g = Glb()
    pos = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], np.float32)
    uv = np.array([[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]])
    if uv_matrix is not None:
        uv = uv @ uv_matrix[:2, :2].T + uv_matrix[:2, 2]
    attrs = {
        "POSITION": g.accessor(pos),
        "NORMAL": g.accessor(np.tile([0.0, 0.0, 1.0], (4, 1))),
        "TEXCOORD_0": g.accessor(uv),
    }
    info: dict[str, Any] = {"index": g.image(checker(n=64), srgb=True)}
    if transform is not None:
        info["extensions"] = {"KHR_texture_transform": transform}
        g.doc["extensionsUsed"] = ["KHR_texture_transform"]
    mat = g.material(
        {
            "name": "checker",
            "pbrMetallicRoughness": {
                "baseColorTexture": info,
                "metallicFactor": 0.0,
                "roughnessFactor": 1.0,
            },
        }
    )
    idx = np.array([0, 1, 2, 0, 2, 3], np.uint16)
    g.mesh([{"attributes": attrs, "indices": g.accessor(idx, USHORT), "material": mat}])
    return g.write(path)


def draco_sphere(path: Path, compressed: bool = True, n: int = 24) -> Path:
    """A unit UV sphere (grey, rough dielectric); ``compressed``: its mesh Draco-encoded
    (``KHR_draco_mesh_compression``, positions quantized to 14 bits, the order kept), else
    plain float accessors."""
    import trimesh

    s = trimesh.creation.uv_sphere(radius=1.0, count=[n, n])
    pos = np.asarray(s.vertices, np.float32)
    nrm = (pos / np.linalg.norm(pos, axis=1, keepdims=True)).astype(np.float32)
    faces = np.asarray(s.faces, np.uint32)
    g = Glb()
    mat = g.material(
        {
            "name": "grey",
            "pbrMetallicRoughness": {
                "baseColorFactor": [0.6, 0.6, 0.6, 1.0],
                "metallicFactor": 0.0,
                "roughnessFactor": 0.8,
            },
        }
    )
    if not compressed:
        attrs = {"POSITION": g.accessor(pos), "NORMAL": g.accessor(nrm)}
        prim = {"attributes": attrs, "indices": g.accessor(faces.ravel(), UINT), "material": mat}
        g.mesh([prim])
        return g.write(path)
    import DracoPy  # noqa: N813

    data = DracoPy.encode(
        pos, faces, quantization_bits=14, preserve_order=True, normals=nrm.astype(np.float64)
    )
    decoded = DracoPy.decode(data)
    ids = {a["attribute_type"]: a["unique_id"] for a in decoded.attributes}
    view = g.view(data)

    def stub(count: int, kind: str, comp: int) -> int:
        g.doc["accessors"].append({"componentType": comp, "count": count, "type": kind})
        return len(g.doc["accessors"]) - 1

    npts = len(decoded.points)
    attrs = {"POSITION": stub(npts, "VEC3", FLOAT), "NORMAL": stub(npts, "VEC3", FLOAT)}
    g.doc["accessors"][attrs["POSITION"]].update(
        {"min": pos.min(0).tolist(), "max": pos.max(0).tolist()}
    )
    ext = {"bufferView": view, "attributes": {"POSITION": ids[0], "NORMAL": ids[1]}}
    prim = {
        "attributes": attrs,
        "indices": stub(len(decoded.faces) * 3, "SCALAR", UINT),
        "material": mat,
        "extensions": {"KHR_draco_mesh_compression": ext},
    }
    g.doc["extensionsUsed"] = ["KHR_draco_mesh_compression"]
    g.doc["extensionsRequired"] = ["KHR_draco_mesh_compression"]
    g.mesh([prim])
    return g.write(path)


def lit_room(path: Path) -> Path:
    """A glTF scene with its own lights (``KHR_lights_punctual``): a grey sphere of radius
    0.5 on a 4×4 m grey floor, a point light of 20 cd 1.5 m above the floor and a spot
    light of 40 cd (45° outer cone, a sharp edge from 43°: Blender's import approximates
    glTF's smooth cone falloff by its own blend, 11% darker here with a 29° inner cone) aimed
    down from the side."""
    import trimesh

    g = Glb()
    grey = g.material(
        {
            "name": "grey",
            "pbrMetallicRoughness": {
                "baseColorFactor": [0.6, 0.6, 0.6, 1.0],
                "metallicFactor": 0.0,
                "roughnessFactor": 0.9,
            },
        }
    )
    floor = np.array([[-2, 0, -2], [2, 0, -2], [2, 0, 2], [-2, 0, 2]], np.float32)
    attrs = {"POSITION": g.accessor(floor), "NORMAL": g.accessor(np.tile([0.0, 1, 0], (4, 1)))}
    idx = np.array([0, 2, 1, 0, 3, 2], np.uint16)
    g.mesh([{"attributes": attrs, "indices": g.accessor(idx, USHORT), "material": grey}])
    s = trimesh.creation.uv_sphere(radius=0.5, count=[24, 24])
    pos = np.asarray(s.vertices, np.float32)
    nrm = pos / np.linalg.norm(pos, axis=1, keepdims=True)
    attrs = {"POSITION": g.accessor(pos), "NORMAL": g.accessor(nrm)}
    faces = np.asarray(s.faces, np.uint32).ravel()
    prim = {"attributes": attrs, "indices": g.accessor(faces, UINT), "material": grey}
    g.mesh([prim], translation=[0.0, 0.5, 0.0])
    lights = [
        {"type": "point", "color": [1.0, 0.9, 0.8], "intensity": 20.0},
        {
            "type": "spot",
            "intensity": 40.0,
            "spot": {"outerConeAngle": 0.785, "innerConeAngle": 0.75},
        },
    ]
    g.doc["extensions"] = {"KHR_lights_punctual": {"lights": lights}}
    g.doc["extensionsUsed"] = ["KHR_lights_punctual"]
    # The point light 1.5 m up; the spot at (1.5, 2, 0) looking at the origin (its -z axis).
    g.doc["nodes"].append(
        {"translation": [0.3, 1.5, 0.4], "extensions": {"KHR_lights_punctual": {"light": 0}}}
    )
    d = np.array([-1.5, -2.0, 0.0]) / 2.5
    axis = np.cross([0.0, 0.0, -1.0], d)
    angle = np.arccos(np.dot([0.0, 0.0, -1.0], d))
    q = [*(axis / np.linalg.norm(axis) * np.sin(angle / 2)), np.cos(angle / 2)]
    g.doc["nodes"].append(
        {
            "translation": [1.5, 2.0, 0.0],
            "rotation": q,
            "extensions": {"KHR_lights_punctual": {"light": 1}},
        }
    )
    g.doc["scenes"][0]["nodes"] += [len(g.doc["nodes"]) - 2, len(g.doc["nodes"]) - 1]
    return g.write(path)
