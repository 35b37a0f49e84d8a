"""``KHR_draco_mesh_compression``: a primitive's attributes and indices decoded by Google's
Draco decoder through the ``DracoPy`` package (the optional dependency ``gi[draco]``).

Without the package, reading such a file is a :class:`~gi.gltf.errors.GltfError` that
names the extension and says how to decompress the file instead
(``npx @gltf-transform/cli copy in.glb out.glb``, which writes uncompressed buffers).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from gi.gltf.errors import GltfError

EXTENSION = "KHR_draco_mesh_compression"
# glTF's integer component types.
_INTEGERS = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5125: np.uint32}
_NO_DECODER = (
    "this file's meshes are Draco-compressed and the Draco decoder is not installed:"
    " `pip install DracoPy` (or gi[draco]), or decompress the file with"
    " `npx @gltf-transform/cli copy IN.glb OUT.glb`"
)


def decode(
    ext: Any, attributes: dict[str, int], accessors: list[dict[str, Any]], data: bytes, where: str
) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """The primitive's attributes (name -> (count, components) array, as its accessors
    describe them: normalized integers become floats) and triangle indices (M, 3) from the
    compressed ``data`` of its ``bufferView``; ``ext`` is the extension object."""
    ew = f"{where}.extensions.{EXTENSION}"
    try:
        import DracoPy  # type: ignore[import-not-found]  # noqa: N813
    except ImportError as e:
        raise GltfError(ew, _NO_DECODER) from e
    ids = ext.get("attributes") if isinstance(ext, dict) else None
    if not isinstance(ids, dict):
        raise GltfError(f"{ew}.attributes", "missing: it maps attribute names to Draco ids")
    try:
        mesh = DracoPy.decode(data)
    except Exception as e:  # the decoder's own errors (corrupt or truncated data)
        raise GltfError(f"{ew}.bufferView", f"cannot decode the Draco data: {e}") from e
    faces = getattr(mesh, "faces", None)
    if faces is None or len(np.asarray(faces)) == 0:
        raise GltfError(f"{ew}.bufferView", "the Draco data is a point cloud, not a mesh")
    out: dict[str, np.ndarray] = {}
    for name, uid in ids.items():
        attr = mesh.get_attribute_by_unique_id(int(uid))
        if attr is None:
            raise GltfError(f"{ew}.attributes.{name}", f"no Draco attribute with id {uid}")
        arr = np.asarray(attr["data"])
        arr = arr.reshape(len(arr), -1)
        acc = accessors[attributes[name]] if name in attributes else {}
        kind = _INTEGERS.get(acc.get("componentType"))
        if acc.get("normalized") and kind is not None:
            # Normalized by the accessor's type (what the encoder quantized to).
            arr = np.maximum(arr.astype(np.float64) / np.iinfo(kind).max, -1.0)
        out[name] = arr
    return out, np.asarray(faces, dtype=np.int64).reshape(-1, 3)
