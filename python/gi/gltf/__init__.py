"""glTF 2.0 (``.gltf`` and ``.glb``) reader for gi's mesh arrays, with numpy only.

gi reads glTF itself rather than through trimesh so that material factors keep their exact
float values (trimesh stores ``baseColorFactor`` as 8-bit), missing factors get the glTF
defaults, and features gi does not render (emission, vertex colours, occlusion maps) are
reported by name instead of dropped. Base colour, metallic-roughness, normal and emissive
textures (``TEXCOORD_0``, repeat wrap) and alpha masks are read into a
:class:`gi.textures.TextureSet`.

Lights (``KHR_lights_punctual``) come out in the file's world space as gi light descriptions.
The extension gives point and spot lights in candela (lm/sr) and directional lights in lux
(lm/m²); gi's are radiometric (W/sr, W/m², per linear RGB channel), so both are divided by
683 lm/W (:data:`LUMENS_PER_WATT`), the luminous efficacy that defines the candela (SI) and
the factor Blender's glTF exporter multiplies by: Blender → glTF → gi gives back the W/sr and
W/m² the exporter started from. Emission (``emissiveFactor`` × ``emissiveTexture`` ×
``KHR_materials_emissive_strength``) has no unit in glTF; it is taken as radiance
(W·sr⁻¹·m⁻²), which is what Blender's exporter writes (emission colour × strength).
"""

from __future__ import annotations

import base64
import json
import struct
import urllib.parse
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from gi.gltf import draco
from gi.gltf.errors import GltfError
from gi.gltf.uv import MaterialUv, apply, transform_tangents
from gi.textures import TextureError, TextureSet, resample

_DTYPES = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5125: np.uint32}
_DTYPES[5126] = np.float32
_COMPONENTS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}
# Why the occlusion map is not read, said once per file.
_OCCLUSION = (
    "ignored: gi computes how much light reaches each point by tracing it, so a baked"
    " ambient-occlusion map would darken what the light transport already shadows"
)
_REPEAT = 10497
# Material extensions gi reads.
_MATERIAL_EXTENSIONS = (
    "KHR_materials_transmission",
    "KHR_materials_ior",
    "KHR_materials_emissive_strength",
)
# Luminous efficacy (lm/W) from KHR_lights_punctual's photometric units to gi's radiometric
# ones: 683 lm/W defines the candela (SI Brochure, 9th ed., 2019, K_cd) and is Blender's
# glTF exporter's PBR_WATTS_TO_LUMENS.
LUMENS_PER_WATT = 683.0


# Required extensions gi can read a file with (what it leaves out is reported).
_READABLE = {
    "KHR_lights_punctual",
    "KHR_materials_transmission",
    "KHR_materials_ior",
    "KHR_materials_emissive_strength",
    "KHR_texture_transform",
    "KHR_mesh_quantization",
    "KHR_draco_mesh_compression",
    "EXT_mesh_gpu_instancing",
}


@dataclass
class GltfMesh:
    """World-space triangles of a glTF scene, with per-face material indices."""

    vertices: np.ndarray  # float64 (N, 3)
    faces: np.ndarray  # int64 (M, 3), counter-clockwise = front
    normals: np.ndarray | None  # float64 (N, 3), zero rows where the file has none
    face_materials: np.ndarray  # int64 (M,), index into `materials`, -1: none
    materials: list[tuple[str, dict[str, Any]]]  # (name, gi material description)
    warnings: dict[str, str] = field(default_factory=dict)  # JSON path -> what is ignored
    uvs: np.ndarray | None = None  # float64 (N, 2), TEXCOORD_0 (v down), zero where none
    lights: list[dict[str, Any]] = field(default_factory=list)  # gi lights, world space
    tangents: np.ndarray | None = None  # float64 (N, 4), gi's convention, zero w: none


def _read_document(path: Path) -> tuple[dict[str, Any], bytes | None]:
    data = path.read_bytes()
    if data[:4] != b"glTF":
        try:
            return json.loads(data.decode("utf-8")), None
        except (UnicodeDecodeError, json.JSONDecodeError) as e:
            raise GltfError("(file)", f"neither GLB nor glTF JSON: {e}") from e
    if len(data) < 20:
        raise GltfError("(file)", "truncated GLB header")
    version, length = struct.unpack_from("<II", data, 4)
    if version != 2:
        raise GltfError("(file)", f"GLB version {version} (gi reads glTF 2)")
    doc, binary, offset = None, None, 12
    while offset + 8 <= min(length, len(data)):
        size, kind = struct.unpack_from("<II", data, offset)
        chunk = data[offset + 8 : offset + 8 + size]
        if kind == 0x4E4F534A:  # "JSON"
            doc = json.loads(chunk.decode("utf-8"))
        elif kind == 0x004E4942 and binary is None:  # "BIN\0"
            binary = chunk
        offset += 8 + size
    if doc is None:
        raise GltfError("(file)", "GLB has no JSON chunk")
    return doc, binary


class _Reader:
    def __init__(self, path: Path, doc: dict[str, Any], glb_bin: bytes | None):
        self.path, self.doc, self.glb_bin = path, doc, glb_bin
        self.buffers: dict[int, bytes] = {}

    def buffer(self, i: int) -> bytes:
        if i not in self.buffers:
            entry = self.doc["buffers"][i]
            uri = entry.get("uri")
            where = f"buffers[{i}].uri"
            if uri is None:
                if self.glb_bin is None:
                    raise GltfError(where, "no URI and no GLB binary chunk")
                data = self.glb_bin
            elif uri.startswith("data:"):
                data = base64.b64decode(uri.split(",", 1)[1])
            else:
                file = self.path.parent / urllib.parse.unquote(uri)
                try:
                    data = file.read_bytes()
                except OSError as e:
                    raise GltfError(where, f"cannot read {file}: {e}") from e
            if len(data) < entry.get("byteLength", 0):
                raise GltfError(where, "shorter than its byteLength")
            self.buffers[i] = data
        return self.buffers[i]

    def accessor(self, i: int) -> np.ndarray:
        """Accessor `i` as an (count, components) array; normalized integers become floats."""
        where = f"accessors[{i}]"
        try:
            acc = self.doc["accessors"][i]
            dtype = np.dtype(_DTYPES[acc["componentType"]]).newbyteorder("<")
            ncomp = _COMPONENTS[acc["type"]]
            count = int(acc["count"])
        except (KeyError, IndexError, TypeError) as e:
            raise GltfError(where, f"malformed accessor ({e!r})") from e
        if "sparse" in acc:
            raise GltfError(f"{where}.sparse", "sparse accessors are not supported")
        if "bufferView" not in acc:
            out = np.zeros((count, ncomp), dtype)
        else:
            view = self.doc["bufferViews"][acc["bufferView"]]
            data = self.buffer(view["buffer"])
            offset = view.get("byteOffset", 0) + acc.get("byteOffset", 0)
            stride = view.get("byteStride") or dtype.itemsize * ncomp
            end = offset + stride * (count - 1) + dtype.itemsize * ncomp if count else offset
            if end > min(len(data), view.get("byteOffset", 0) + view["byteLength"]):
                raise GltfError(where, "reads past the end of its buffer view")
            out = np.ndarray(
                (count, ncomp), dtype, buffer=data, offset=offset, strides=(stride, dtype.itemsize)
            ).copy()
        if acc.get("normalized") and dtype.kind in "iu":
            info = np.iinfo(dtype)
            return np.maximum(out.astype(np.float64) / info.max, -1.0)
        return out

    def image(self, i: int, textures: TextureSet, colour: bool) -> str:
        """Image `i` read into `textures` (files by path; embedded ones via a temporary file)."""
        img = self.doc["images"][i]
        uri = img.get("uri")
        if uri is not None and not uri.startswith("data:"):
            return textures.add(self.path.parent / urllib.parse.unquote(uri), colour)
        key = f"{textures.name(self.path)}#image{i}"
        if (key if colour else f"{key}#linear") in textures.arrays:
            return key if colour else f"{key}#linear"
        if uri is not None:
            data = base64.b64decode(uri.split(",", 1)[1])
            mime = uri[5:].split(";", 1)[0]
        else:
            view = self.doc["bufferViews"][img["bufferView"]]
            start = view.get("byteOffset", 0)
            data = self.buffer(view["buffer"])[start : start + view["byteLength"]]
            mime = img.get("mimeType", "")
        suffix = {"image/png": ".png", "image/jpeg": ".jpg"}.get(mime, ".png")
        import tempfile

        with tempfile.TemporaryDirectory() as tmp:
            file = Path(tmp) / f"image{i}{suffix}"
            file.write_bytes(data)
            name = textures.add(file, colour)
            arr = textures.arrays.pop(name)
        return textures.add_array(key if colour else f"{key}#linear", arr)


def _trs_matrices(t: np.ndarray, q: np.ndarray, s: np.ndarray) -> np.ndarray:
    """(n, 4, 4) matrices T · R(q) · diag(s) from (n, 3) translations, (n, 4) unit
    quaternions (x, y, z, w) and (n, 3) scales, as :func:`_node_matrix` builds one."""
    x, y, z, w = q.T
    r = np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], -1),
            np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], -1),
            np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], -1),
        ],
        axis=1,
    )
    m = np.broadcast_to(np.eye(4), (len(t), 4, 4)).copy()
    m[:, :3, :3] = r * s[:, None, :]  # R · diag(s)
    m[:, :3, 3] = t
    return m


def _gpu_instances(
    reader: _Reader, node: dict[str, Any], ni: int, warn: dict[str, str]
) -> np.ndarray | None:
    """The node's ``EXT_mesh_gpu_instancing`` placements as (n, 4, 4) matrices in the
    node's frame (TRANSLATION, ROTATION, SCALE accessors; missing ones are identity), or
    None without the extension."""
    ext = node.get("extensions", {}).get("EXT_mesh_gpu_instancing")
    if ext is None:
        return None
    where = f"nodes[{ni}].extensions.EXT_mesh_gpu_instancing.attributes"
    attrs = ext.get("attributes", {}) if isinstance(ext, dict) else {}
    known = {"TRANSLATION": 3, "ROTATION": 4, "SCALE": 3}
    arrays = {}
    for name, width in known.items():
        if name in attrs:
            a = reader.accessor(attrs[name]).astype(np.float64)
            if a.ndim != 2 or a.shape[1] != width:
                raise GltfError(f"{where}.{name}", f"must be VEC{width}")
            arrays[name] = a
    for name in attrs:
        if name not in known and not name.startswith("_"):
            warn[f"{where}.{name}"] = "this instance attribute is ignored"
    counts = {len(a) for a in arrays.values()}
    if len(counts) != 1:
        raise GltfError(where, "needs TRANSLATION, ROTATION or SCALE, all of one count")
    n = counts.pop()
    t = arrays.get("TRANSLATION", np.zeros((n, 3)))
    q = arrays.get("ROTATION", np.tile([0.0, 0.0, 0.0, 1.0], (n, 1)))
    s = arrays.get("SCALE", np.ones((n, 3)))
    return _trs_matrices(t, q, s)


def _node_matrix(node: dict[str, Any]) -> np.ndarray:
    if "matrix" in node:
        return np.asarray(node["matrix"], dtype=np.float64).reshape(4, 4).T  # column-major
    t = np.asarray(node.get("translation", [0, 0, 0]), dtype=np.float64)
    x, y, z, w = np.asarray(node.get("rotation", [0, 0, 0, 1]), dtype=np.float64)
    s = np.asarray(node.get("scale", [1, 1, 1]), dtype=np.float64)
    r = np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )
    m = np.eye(4)
    m[:3, :3] = r * s  # R · diag(s)
    m[:3, 3] = t
    return m


def _triangles(mode: int, idx: np.ndarray, where: str) -> np.ndarray | None:
    if mode == 4:
        return idx[: len(idx) // 3 * 3].reshape(-1, 3)
    if mode == 5:  # strip: every other triangle reversed to keep the winding
        n = len(idx) - 2
        if n <= 0:
            return np.zeros((0, 3), np.int64)
        tri = np.stack([idx[:-2], idx[1:-1], idx[2:]], axis=1)
        tri[1::2] = tri[1::2][:, [1, 0, 2]]
        return tri
    if mode == 6:  # fan
        if len(idx) < 3:
            return np.zeros((0, 3), np.int64)
        return np.stack([np.full(len(idx) - 2, idx[0]), idx[1:-1], idx[2:]], axis=1)
    return None  # points and lines have no surface


def _texture(
    reader: _Reader | None,
    textures: TextureSet | None,
    info: dict[str, Any],
    where: str,
    colour: bool,
    warn: dict[str, str],
    uv: MaterialUv | None = None,
) -> str | None:
    """The texture a material's texture-info refers to, read into `textures`; None (with a
    warning) where gi cannot use it. Its texture-coordinate set and transform go to `uv`."""
    if uv is not None:
        uv.add(info, where)
    if reader is None or textures is None:
        return None
    doc = reader.doc
    try:
        tex = doc["textures"][info["index"]]
        source = tex["source"]
    except (KeyError, IndexError, TypeError):
        warn[where] = "the texture has no image gi can read; the constant factor is used"
        return None
    sampler = doc.get("samplers", [])[tex["sampler"]] if "sampler" in tex else {}
    if sampler.get("wrapS", _REPEAT) != _REPEAT or sampler.get("wrapT", _REPEAT) != _REPEAT:
        warn[f"{where}.sampler"] = "only repeat wrapping is supported; it repeats"
    try:
        return reader.image(source, textures, colour)
    except (TextureError, OSError, KeyError, IndexError, ValueError) as e:
        warn[where] = f"cannot read the image ({e}); the constant factor is used"
        return None


def _material(
    doc: dict[str, Any],
    i: int,
    warn: dict[str, str],
    reader: _Reader | None = None,
    textures: TextureSet | None = None,
    uv: MaterialUv | None = None,
) -> dict[str, Any]:
    """glTF metallic-roughness (with the glTF defaults) onto the uber BSDF; the texture
    coordinates its textures read are collected in `uv`."""
    mat = doc["materials"][i]
    where = f"materials[{i}]"
    pbr = mat.get("pbrMetallicRoughness", {})
    base = np.asarray(pbr.get("baseColorFactor", [1, 1, 1, 1]), dtype=np.float64)[:3]
    metal = float(pbr.get("metallicFactor", 1.0))
    rough = float(pbr.get("roughnessFactor", 1.0))
    base, metal, rough = np.clip(base, 0, 1), min(max(metal, 0.0), 1.0), min(max(rough, 0.0), 1)
    ext = mat.get("extensions", {})
    trans = float(ext.get("KHR_materials_transmission", {}).get("transmissionFactor", 0.0))
    trans = min(max(trans, 0.0), 1.0)
    ior = float(ext.get("KHR_materials_ior", {}).get("ior", 1.5))
    dielectric = base * (1.0 - metal)
    desc: dict[str, Any] = {
        "diffuse": (dielectric * (1.0 - trans)).tolist(),
        "specular": (0.04 * (1.0 - metal) + base * metal).tolist(),
        "roughness": rough,
        "fresnel": True,
    }
    if trans > 0:
        desc["transmission"] = (dielectric * trans).tolist()
        desc["ior"] = min(max(ior, 1.0), 4.0)
    pw = f"{where}.pbrMetallicRoughness"
    base_tex = mr_tex = None
    if "baseColorTexture" in pbr:
        base_tex = _texture(
            reader, textures, pbr["baseColorTexture"], f"{pw}.baseColorTexture", True, warn, uv
        )
    if "metallicRoughnessTexture" in pbr:
        mr_tex = _texture(
            reader,
            textures,
            pbr["metallicRoughnessTexture"],
            f"{pw}.metallicRoughnessTexture",
            False,
            warn,
            uv,
        )
    if textures is not None and (base_tex or mr_tex):
        _bake_metallic(desc, textures, base_tex, mr_tex, base, metal, trans, i)
    if "normalTexture" in mat:
        info = mat["normalTexture"]
        normal = _texture(reader, textures, info, f"{where}.normalTexture", False, warn, uv)
        if normal:
            desc["normal_texture"] = normal
            if float(info.get("scale", 1.0)) != 1.0:
                warn[f"{where}.normalTexture.scale"] = "normal map scales are ignored (1 is used)"
    if "occlusionTexture" in mat:
        warn.setdefault("materials[*].occlusionTexture", f"{_OCCLUSION} (first: {where})")
    _emission(desc, mat, where, warn, reader, textures, uv)
    mode = mat.get("alphaMode", "OPAQUE")
    if mode != "OPAQUE":
        cutoff = float(mat.get("alphaCutoff", 0.5)) if mode == "MASK" else 0.5
        if mode == "BLEND":
            warn[f"{where}.alphaMode"] = "blending is not supported; it is a mask at alpha 0.5"
        alpha = float(pbr.get("baseColorFactor", [1, 1, 1, 1])[3])
        if base_tex is not None and textures is not None:
            # Coverage = factor × texture alpha: the texture's alpha against cutoff / factor.
            desc["alpha_texture"] = base_tex
            desc["alpha_cutoff"] = min(cutoff / alpha, 1.0) if alpha > 0 else 1.0
            if alpha <= 0 or cutoff / alpha > 1.0:
                desc["alpha_texture"] = textures.add_array(
                    "(transparent)", np.zeros((1, 1, 4), np.float32)
                )
        elif alpha < cutoff and textures is not None:
            # No texture and a factor below the cutoff: the whole surface is cut out.
            desc["alpha_texture"] = textures.add_array(
                "(transparent)", np.zeros((1, 1, 4), np.float32)
            )
            desc["alpha_cutoff"] = 0.5
    for name in ext:
        if name not in _MATERIAL_EXTENSIONS:
            warn[f"{where}.extensions.{name}"] = "this material extension is ignored"
    return desc


def _emission(
    desc: dict[str, Any],
    mat: dict[str, Any],
    where: str,
    warn: dict[str, str],
    reader: _Reader | None,
    textures: TextureSet | None,
    uv: MaterialUv | None = None,
) -> None:
    """glTF emission onto the material: ``emission`` = ``emissiveFactor`` × the
    ``KHR_materials_emissive_strength`` (radiance, W·sr⁻¹·m⁻²), ``emission_texture`` =
    ``emissiveTexture`` (sRGB); a ``doubleSided`` material emits from both faces."""
    factor = np.asarray(mat.get("emissiveFactor", [0, 0, 0]), dtype=np.float64)[:3]
    strength = mat.get("extensions", {}).get("KHR_materials_emissive_strength", {})
    emission = np.maximum(factor, 0.0) * max(float(strength.get("emissiveStrength", 1.0)), 0.0)
    if not emission.max() > 0:
        return  # glTF's default factor is black: an emissive texture alone emits nothing
    desc["emission"] = emission.tolist()
    if mat.get("doubleSided", False):
        desc["two_sided"] = True
    if "emissiveTexture" in mat:
        info = mat["emissiveTexture"]
        tex = _texture(reader, textures, info, f"{where}.emissiveTexture", True, warn, uv)
        if tex:
            desc["emission_texture"] = tex


def _light(
    doc: dict[str, Any], ni: int, world: np.ndarray, warn: dict[str, str]
) -> dict[str, Any] | None:
    """The ``KHR_lights_punctual`` light of node ``ni`` (world transform ``world``) as a gi
    light: positions from the node's origin, directions along its -z axis; intensities
    divided by :data:`LUMENS_PER_WATT` (candela → W/sr, lux → W/m²) times ``color``."""
    where = f"nodes[{ni}].extensions.KHR_lights_punctual"
    try:
        index = doc["nodes"][ni]["extensions"]["KHR_lights_punctual"]["light"]
        light = doc["extensions"]["KHR_lights_punctual"]["lights"][index]
        kind = light["type"]
    except (KeyError, IndexError, TypeError):
        warn[where] = "names no light of the file's KHR_lights_punctual lights; ignored"
        return None
    lw = f"extensions.KHR_lights_punctual.lights[{index}]"
    color = np.maximum(np.asarray(light.get("color", [1, 1, 1]), dtype=np.float64)[:3], 0.0)
    value = (color * max(float(light.get("intensity", 1.0)), 0.0) / LUMENS_PER_WATT).tolist()
    direction = world[:3, :3] @ np.array([0.0, 0.0, -1.0])
    with np.errstate(all="ignore"):
        direction = (direction / np.linalg.norm(direction)).tolist()
    position = world[:3, 3].tolist()
    if kind in ("point", "spot") and "range" in light:
        warn[f"{lw}.range"] = "ranges are ignored: the light falls off as 1/d² without a cutoff"
    if kind == "point":
        return {"type": "point", "position": position, "intensity": value}
    if kind == "directional":
        return {"type": "directional", "direction": direction, "irradiance": value}
    if kind != "spot":
        warn[f"{lw}.type"] = f"unknown light type {kind!r}; ignored"
        return None
    spot = light.get("spot", {})
    outer = np.degrees(float(spot.get("outerConeAngle", np.pi / 4)))
    inner = np.degrees(float(spot.get("innerConeAngle", 0.0)))
    if outer >= 89.9:
        warn[f"{lw}.spot.outerConeAngle"] = "gi's spot lights reach at most 89.9°; clamped"
        outer = 89.9
    return {
        "type": "spot",
        "position": position,
        "direction": direction,
        "intensity": value,
        "inner_angle": float(min(max(inner, 0.0), outer)),
        "outer_angle": float(outer),
    }


def _bake_metallic(
    desc: dict[str, Any],
    textures: TextureSet,
    base_tex: str | None,
    mr_tex: str | None,
    base: np.ndarray,
    metal: float,
    trans: float,
    i: int,
) -> None:
    """Textured metallic-roughness onto the uber BSDF's maps. Roughness is the map's green
    channel (times the factor, as the core does). Diffuse and specular depend on base colour
    and metallic together: unless the material is a plain dielectric with a base-colour
    texture (diffuse = base texture × factor, specular 0.04), they are baked per texel at the
    larger map's resolution (nearest-texel resampling)."""
    if mr_tex:
        desc["roughness_texture"] = mr_tex
    if base_tex and not mr_tex and metal == 0.0:
        desc["diffuse_texture"] = base_tex
        return
    arrays = [textures.arrays[k] for k in (base_tex, mr_tex) if k]
    h = max(a.shape[0] for a in arrays)
    w = max(a.shape[1] for a in arrays)
    rgb = np.broadcast_to(base, (h, w, 3)).astype(np.float32)
    if base_tex:
        rgb = rgb * resample(textures.arrays[base_tex], h, w)[..., :3]
    m = np.full((h, w, 1), metal, np.float32)
    if mr_tex:
        m = m * resample(textures.arrays[mr_tex], h, w)[..., 2:3]
    one = np.ones((h, w, 1), np.float32)
    diffuse = np.concatenate([rgb * (1.0 - m), one], axis=2)
    specular = np.concatenate([0.04 * (1.0 - m) + rgb * m, one], axis=2)
    key = f"{base_tex or mr_tex}#material{i}"
    desc["diffuse_texture"] = textures.add_array(f"{key}#diffuse", diffuse)
    desc["specular_texture"] = textures.add_array(f"{key}#specular", specular)
    # The maps hold the colours: the factors become 1 (transmission keeps its share).
    desc["diffuse"] = [1.0 - trans] * 3
    desc["specular"] = [1.0, 1.0, 1.0]
    if trans > 0:
        desc["transmission"] = [trans] * 3


@dataclass
class GltfPrimitive:
    """One mesh primitive's triangles in the mesh's own frame."""

    vertices: np.ndarray  # float64 (N, 3)
    faces: np.ndarray  # int64 (M, 3), counter-clockwise = front
    normals: np.ndarray | None  # float64 (N, 3) as stored (not normalised), None: none
    uvs: np.ndarray  # float64 (N, 2), TEXCOORD_0 (v down), zero where none
    material: int  # index into `GltfScene.materials`, -1: none
    index: int = 0  # the primitive's index in its glTF mesh
    # float64 (N, 4) tangents in gi's convention (TANGENT with w negated), None: none
    tangents: np.ndarray | None = None


@dataclass
class GltfInstance:
    """A node that places a mesh: the glTF mesh index and the node's world matrix."""

    node: int
    mesh: int
    matrix: np.ndarray  # float64 (4, 4), mesh -> world
    instance: int | None = None  # the node's EXT_mesh_gpu_instancing placement, if any


@dataclass
class GltfCamera:
    """The first perspective camera of the default scene, in world space."""

    node: int
    position: list[float]
    look_at: list[float]
    up: list[float]
    yfov: float  # degrees
    aspect: float | None


@dataclass
class GltfScene:
    """The default scene of a glTF file as meshes in their own frames and the nodes that
    place them (nodes that share a mesh share its primitives)."""

    meshes: dict[int, list[GltfPrimitive]]  # glTF mesh index -> its surface primitives
    instances: list[GltfInstance]
    materials: list[tuple[str, dict[str, Any]]]  # (name, gi material description)
    warnings: dict[str, str] = field(default_factory=dict)  # JSON path -> what is ignored
    lights: list[dict[str, Any]] = field(default_factory=list)  # gi lights, world space
    camera: GltfCamera | None = None


# glTF's default material (no `material` on a primitive): white, metallic 1, roughness 1.
DEFAULT_MATERIAL_NAME = "(glTF default)"


def default_material() -> dict[str, Any]:
    """The gi description of glTF's default material."""
    return _material({"materials": [{"name": DEFAULT_MATERIAL_NAME}]}, 0, {})


class _SceneReader:
    """Reads meshes (once each, in the order nodes first use them) and materials (once
    each, in the order primitives first use them)."""

    def __init__(self, path: Path, textures: TextureSet):
        self.path, self.textures = path, textures
        doc, glb_bin = _read_document(path)
        unsupported = [e for e in doc.get("extensionsRequired", []) if e not in _READABLE]
        if unsupported:
            raise GltfError("extensionsRequired", f"unsupported extension {unsupported[0]}")
        self.doc = doc
        self.reader = _Reader(path, doc, glb_bin)
        self.warn: dict[str, str] = {}
        self.used: dict[int, int] = {}  # glTF material index -> our index
        self.materials: list[tuple[str, dict[str, Any]]] = []
        self.names: set[str] = set()
        self.meshes: dict[int, list[GltfPrimitive]] = {}
        # Our material index -> the TEXCOORD set and transform its textures read.
        self.uvs: dict[int, tuple[int, np.ndarray | None]] = {}

    def material(self, mi: int) -> int:
        if mi not in self.used:
            doc = self.doc
            uv = MaterialUv()
            desc = _material(doc, mi, self.warn, self.reader, self.textures, uv)
            self.uvs[len(self.materials)] = uv.resolve()
            base = f"{self.path.name}:{doc['materials'][mi].get('name') or f'material{mi}'}"
            name = base if base not in self.names else f"{base}#{mi}"
            self.names.add(name)
            self.used[mi] = len(self.materials)
            self.materials.append((name, desc))
        return self.used[mi]

    def mesh(self, mi: int) -> list[GltfPrimitive]:
        if mi not in self.meshes:
            self.meshes[mi] = [p for p in self._primitives(mi) if p is not None]
        return self.meshes[mi]

    def _primitives(self, mi: int) -> list[GltfPrimitive | None]:
        out: list[GltfPrimitive | None] = []
        for pi, prim in enumerate(self.doc["meshes"][mi]["primitives"]):
            out.append(self._primitive(prim, f"meshes[{mi}].primitives[{pi}]", pi))
        return out

    def _attributes(
        self, prim: dict[str, Any], where: str
    ) -> tuple[dict[str, np.ndarray], np.ndarray | None]:
        """The primitive's attribute arrays by name and its indices (None: none), read
        from its accessors or decoded from its Draco data."""
        attrs = prim.get("attributes", {})
        ext = prim.get("extensions", {}).get(draco.EXTENSION)
        if ext is not None:
            try:
                view = self.doc["bufferViews"][ext["bufferView"]]
                start = view.get("byteOffset", 0)
                data = self.reader.buffer(view["buffer"])[start : start + view["byteLength"]]
            except (KeyError, IndexError, TypeError) as e:
                ew = f"{where}.extensions.{draco.EXTENSION}.bufferView"
                raise GltfError(ew, f"names no buffer view ({e!r})") from e
            acc = self.doc.get("accessors", [])
            arrays, faces = draco.decode(ext, attrs, acc, data, where)
            # Attributes the compressed data leaves out are read from their accessors.
            for name, i in attrs.items():
                arrays.setdefault(name, self.reader.accessor(i))
            return arrays, faces.ravel()
        arrays = {name: self.reader.accessor(i) for name, i in attrs.items() if name in _READ}
        if "indices" in prim:
            return arrays, self.reader.accessor(prim["indices"]).astype(np.int64).ravel()
        return arrays, None

    def _primitive(self, prim: dict[str, Any], where: str, pi: int) -> GltfPrimitive | None:
        warn = self.warn
        attrs = prim.get("attributes", {})
        if "POSITION" not in attrs:
            return None
        arrays, idx = self._attributes(prim, where)
        p = arrays["POSITION"].astype(np.float64)[:, :3]
        if idx is None:
            idx = np.arange(len(p), dtype=np.int64)
        tri = _triangles(prim.get("mode", 4), idx.astype(np.int64), where)
        if tri is None:
            warn[f"{where}.mode"] = "points and lines are skipped (no surface)"
            return None
        if len(tri) == 0:
            return None
        if tri.min() < 0 or tri.max() >= len(p):
            raise GltfError(f"{where}.indices", "index out of range")
        normals = None
        if "NORMAL" in arrays:
            normals = arrays["NORMAL"].astype(np.float64)[:, :3]
        mat = prim.get("material")
        material = -1 if mat is None else self.material(mat)
        coord, transform = self.uvs.get(material, (0, None))
        name = f"TEXCOORD_{coord}"
        if name in arrays:
            uv = arrays[name].astype(np.float64)[:, :2]
            uv = np.nan_to_num(uv) if len(uv) == len(p) else np.zeros((len(p), 2))
            uv = apply(uv, transform)
        elif coord != 0:
            raise GltfError(f"{where}.attributes", f"no {name}, which its material's textures read")
        else:
            uv = np.zeros((len(p), 2))
        if prim.get("targets"):
            warn[f"{where}.targets"] = "morph targets are ignored (the base shape is used)"
        tangents = _tangents(arrays, len(p), where) if "TANGENT" in arrays else None
        if tangents is not None and transform is not None:
            n = normals if normals is not None else _vertex_normals(p, tri)
            tangents = transform_tangents(tangents, _unit(n), transform)
        for a in attrs:
            if a.startswith("COLOR_"):
                warn[f"{where}.attributes.{a}"] = "vertex colours are not supported"
        return GltfPrimitive(p, tri, normals, uv, material, pi, tangents)


# Attributes the reader uses (others, e.g. JOINTS_0, are not read).
_READ = {"POSITION", "NORMAL", "TANGENT", *(f"TEXCOORD_{i}" for i in range(8))}


def _unit(v: np.ndarray) -> np.ndarray:
    with np.errstate(all="ignore"):
        return np.nan_to_num(v / np.linalg.norm(v, axis=1, keepdims=True))


def _vertex_normals(p: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """Area-weighted vertex normals of triangles ``tri`` (M, 3) over positions ``p``."""
    face = np.cross(p[tri[:, 1]] - p[tri[:, 0]], p[tri[:, 2]] - p[tri[:, 0]])
    n = np.zeros_like(p)
    for k in range(3):
        np.add.at(n, tri[:, k], face)
    return n


def _tangents(arrays: dict[str, np.ndarray], n: int, where: str) -> np.ndarray:
    """A primitive's ``TANGENT`` (xyz, w = ±1: glTF's bitangent is w · n × t, up the image)
    in gi's convention, w negated (its bitangent runs down the image, along +v)."""
    t = arrays["TANGENT"].astype(np.float64)
    tw = f"{where}.attributes.TANGENT"
    if t.ndim != 2 or t.shape[1] != 4 or len(t) != n:
        raise GltfError(tw, "must be VEC4 with one tangent per vertex")
    if not np.isfinite(t).all():
        raise GltfError(
            tw, f"tangent {int(np.flatnonzero(~np.isfinite(t).all(axis=1))[0])} is not finite"
        )
    out = t.copy()
    out[:, 3] = np.where(t[:, 3] < 0, 1.0, -1.0)
    return out


def _camera(
    doc: dict[str, Any], ni: int, world: np.ndarray, warn: dict[str, str]
) -> GltfCamera | None:
    """Node ``ni``'s camera (world transform ``world``; it looks down its -z axis, +y up),
    or None (with a warning) for an orthographic or malformed one."""
    where = f"nodes[{ni}].camera"
    try:
        cam = doc["cameras"][doc["nodes"][ni]["camera"]]
        kind = cam["type"]
    except (KeyError, IndexError, TypeError):
        warn[where] = "names no camera of the file; ignored"
        return None
    if kind != "perspective":
        warn[where] = f"{kind} cameras are not supported; ignored"
        return None
    persp = cam.get("perspective", {})
    position = world[:3, 3]
    forward = world[:3, :3] @ np.array([0.0, 0.0, -1.0])
    up = world[:3, :3] @ np.array([0.0, 1.0, 0.0])
    aspect = persp.get("aspectRatio")
    return GltfCamera(
        node=ni,
        position=position.tolist(),
        look_at=(position + forward).tolist(),
        up=up.tolist(),
        yfov=float(np.degrees(float(persp.get("yfov", np.radians(40.0))))),
        aspect=None if aspect is None else float(aspect),
    )


def read_gltf(path: Path, textures: TextureSet | None = None) -> GltfScene:
    """Reads the default scene of a glTF file as its meshes, each in its own frame and read
    once, and the nodes that place them (world matrices); its textures go into `textures`
    (without one, textures are reported and not read)."""
    r = _SceneReader(path, TextureSet() if textures is None else textures)
    doc, warn = r.doc, r.warn
    if doc.get("animations"):
        warn["animations"] = "animations are ignored (the rest pose is used)"
    nodes = doc.get("nodes", [])
    scenes = doc.get("scenes", [])
    if scenes:
        roots = scenes[doc.get("scene", 0)].get("nodes", [])
    else:
        children = {c for n in nodes for c in n.get("children", [])}
        roots = [i for i in range(len(nodes)) if i not in children]
    out = GltfScene({}, [], r.materials, warn)
    stack = [(root, np.eye(4), 0) for root in reversed(roots)]
    while stack:
        ni, parent, depth = stack.pop()
        if depth > 256:
            raise GltfError(f"nodes[{ni}]", "node hierarchy is cyclic or deeper than 256")
        node = nodes[ni]
        world = parent @ _node_matrix(node)
        stack.extend((c, world, depth + 1) for c in reversed(node.get("children", [])))
        if "KHR_lights_punctual" in node.get("extensions", {}):
            light = _light(doc, ni, world, warn)
            if light is not None:
                out.lights.append(light)
        if "camera" in node and out.camera is None:
            out.camera = _camera(doc, ni, world, warn)
        if "mesh" not in node:
            continue
        placements = _gpu_instances(r.reader, node, ni, warn)
        worlds = world[None] if placements is None else world @ placements
        with np.errstate(all="ignore"):
            lin = worlds[:, :3, :3]
            finite = np.isfinite(lin).all(axis=(1, 2))
            det = np.where(finite, np.linalg.det(np.where(finite[:, None, None], lin, 0)), np.nan)
        if not (np.isfinite(det) & (np.abs(det) > 1e-30)).all():
            raise GltfError(
                f"nodes[{ni}]", "the world transform is singular or not finite (e.g. a zero scale)"
            )
        r.mesh(node["mesh"])
        for k, w in enumerate(worlds):
            out.instances.append(
                GltfInstance(ni, node["mesh"], w, None if placements is None else k)
            )
    out.meshes = r.meshes
    return out


def load_gltf(path: Path, textures: TextureSet | None = None) -> GltfMesh:
    """Reads the default scene of a glTF file into world-space triangles (every node's
    copy of its mesh; :func:`read_gltf` keeps shared meshes shared); its textures go into
    `textures` (without one, textures are reported and not read)."""
    scene = read_gltf(path, textures)
    verts, faces, normals, face_mats, uvs = [], [], [], [], []
    tangents: list[np.ndarray | None] = []
    offset = 0
    for inst in scene.instances:
        world = inst.matrix
        lin = world[:3, :3]
        mirrored = np.linalg.det(lin) < 0
        with np.errstate(all="ignore"):
            normal_xf = np.linalg.inv(lin).T
        for prim in scene.meshes[inst.mesh]:
            p, tri = prim.vertices, prim.faces
            if mirrored:  # a mirroring transform turns the winding inside out
                tri = tri[:, [0, 2, 1]]
            verts.append(p @ world[:3, :3].T + world[:3, 3])
            if prim.normals is not None:
                n = prim.normals @ normal_xf.T
                with np.errstate(all="ignore"):
                    n /= np.linalg.norm(n, axis=1, keepdims=True)
                normals.append(np.nan_to_num(n, nan=0.0, posinf=0.0, neginf=0.0))
            else:
                normals.append(None)
            uvs.append(prim.uvs)
            tangents.append(_placed_tangents(prim.tangents, lin, mirrored))
            faces.append(tri + offset)
            offset += len(p)
            face_mats.append(np.full(len(tri), prim.material, np.int64))
    warn, lights, materials = scene.warnings, scene.lights, list(scene.materials)
    if not faces:
        none = np.zeros((0, 3))
        return GltfMesh(none, none.astype(np.int64), None, np.zeros(0), [], warn, None, lights)
    any_normals = any(n is not None for n in normals)
    face_materials = np.concatenate(face_mats)
    if materials and (face_materials < 0).any():
        # Primitives without a material get glTF's default one (white, metallic 1, rough 1).
        materials.append((f"{path.name}:{DEFAULT_MATERIAL_NAME}", default_material()))
        face_materials[face_materials < 0] = len(materials) - 1
    return GltfMesh(
        vertices=np.concatenate(verts),
        faces=np.concatenate(faces),
        normals=(
            np.concatenate(
                [
                    n if n is not None else np.zeros_like(v)
                    for n, v in zip(normals, verts, strict=True)
                ]
            )
            if any_normals
            else None
        ),
        face_materials=face_materials,
        materials=materials,
        warnings=warn,
        uvs=np.concatenate(uvs),
        lights=lights,
        tangents=(
            np.concatenate(
                [
                    t if t is not None else np.zeros((len(v), 4))
                    for t, v in zip(tangents, verts, strict=True)
                ]
            )
            if any(t is not None for t in tangents)
            else None
        ),
    )


def _placed_tangents(t: np.ndarray | None, lin: np.ndarray, mirrored: bool) -> np.ndarray | None:
    """Tangents (gi's convention) placed by a node's linear map: xyz mapped and normalized,
    w negated by a mirroring map (as the core places an object's tangents)."""
    if t is None:
        return None
    xyz = t[:, :3] @ lin.T
    with np.errstate(all="ignore"):
        xyz = np.nan_to_num(xyz / np.linalg.norm(xyz, axis=1, keepdims=True))
    return np.concatenate([xyz, t[:, 3:] * (-1.0 if mirrored else 1.0)], axis=1)
