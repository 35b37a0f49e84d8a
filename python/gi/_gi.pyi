"""Type stubs of the native module ``gi._gi`` (checked by ``mypy.stubtest`` in the tests)."""

from collections.abc import Callable
from typing import Any, final

import numpy as np
import numpy.typing as npt

__version__: str

class GiError(Exception): ...
class SceneError(GiError): ...
class SettingError(GiError): ...
class GpuError(GiError): ...
class RenderCancelled(GiError): ...

# (vertices (N, 3), faces (M, 3), normals (N, 3) or None (zero rows: none for that vertex),
# materials as JSON `[[name, material], ...]` or None, per-face index into them (M,) or None)
_MeshArrays = tuple[
    npt.NDArray[np.float32],
    npt.NDArray[np.uint32],
    npt.NDArray[np.float32] | None,
    str | None,
    npt.NDArray[np.uint32] | None,
]

@final
class Scene:
    @staticmethod
    def from_json(
        text: str, source: str = ..., meshes: dict[str, _MeshArrays] | None = None
    ) -> Scene: ...
    @staticmethod
    def builtin(name: str) -> Scene: ...
    @property
    def source(self) -> str: ...
    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    @property
    def triangle_count(self) -> int: ...
    @property
    def light_count(self) -> int: ...
    @property
    def material_names(self) -> list[str]: ...
    @property
    def total_power(self) -> tuple[float, float, float]: ...
    def mesh_arrays(self) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.uint32]]: ...
    def intersect(
        self, origins: npt.NDArray[np.float32], directions: npt.NDArray[np.float32]
    ) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.int64]]: ...
    def build_bvh(self) -> None: ...

def builtin_scenes() -> list[tuple[str, str]]: ...
def builtin_json(name: str) -> str: ...
def methods() -> list[str]: ...
def render(
    scene: Scene,
    method: str = "path",
    spp: int = 64,
    width: int | None = None,
    height: int | None = None,
    seed: int = 0,
    max_depth: int = 64,
    light_paths: int | None = None,
    photons: int = 200_000,
    k: int = 100,
    max_radius: float | None = None,
    kernel: str = "cone",
    smoothing: float = 1.0,
    leaf_size: int | None = None,
    kernel_scale: float = 1.0,
    subsample: int = 2,
    footprint_volumes: bool = False,
    boundary_compensation: bool = True,
    volume_shape: str = "auto",
    adapter: str | None = None,
    shadow_map_size: int = 1024,
    progress: Callable[[str, float], bool | None] | None = None,
) -> dict[str, Any]: ...
def adapter_report(adapter: str | None = None) -> str: ...
def footprint_radii(
    scene: Scene,
    photons: int = 200_000,
    seed: int = 0,
    smoothing: float = 1.0,
    percentiles: list[float] = ...,
) -> dict[str, tuple[int, list[float]]]: ...
