"""gi: global illumination by image-space photon mapping.

>>> import gi
>>> scene = gi.load_scene("cornell")            # a built-in name or a JSON scene file
>>> result = gi.render(scene, method="path", spp=64)
>>> result.radiance.shape                       # (height, width, 3) float32, W·sr⁻¹·m⁻²
>>> gi.save_image("cornell.png", result.radiance)
"""

import atexit
import os

# Mesa's device-select Vulkan layer tries to reach a Wayland display and prints
# "XDG_RUNTIME_DIR is invalid" on headless machines; gi chooses adapters itself, so skip it.
os.environ.setdefault("NODEVICE_SELECT", "1")

from gi._gi import (  # noqa: E402
    GiError,
    GpuError,
    InternalError,
    OutOfMemoryError,
    RenderCancelled,
    RenderStats,
    RenderWarning,
    Scene,
    SceneError,
    SettingError,
    __version__,
    _wait_gpu_idle,
    adapter_report,
    builtin_json,
    builtin_scenes,
    footprint_radii,
    gpu_counters,
    methods,
)

# lavapipe runs submitted GPU work on its own threads; a process that exits while they still
# work (after a failed or interrupted frame) crashes in LLVM's static destructors.
atexit.register(_wait_gpu_idle)

from gi._checks import OutputError  # noqa: E402
from gi.animation import animation_updates  # noqa: E402
from gi.batch import render_batch  # noqa: E402  (imports Ray only when called)
from gi.denoising import denoise  # noqa: E402
from gi.display import to_display  # noqa: E402
from gi.io import read_channels, read_image, save_image, save_layers, save_result  # noqa: E402
from gi.meshes import AssetWarning  # noqa: E402
from gi.render import (  # noqa: E402
    DEFAULT_METHOD,
    Renderer,
    method_options,
    options_table,
    render,
    render_animation,
)
from gi.result import RenderResult  # noqa: E402
from gi.scene import SceneWarning, load_scene  # noqa: E402
from gi.viewer import view  # noqa: E402  (imports aiohttp only when called)


def _present_as_gi() -> None:
    """Tracebacks, warnings and reprs name gi's exception and warning classes as users
    import them: ``gi.SceneError``, not ``_gi.SceneError``; the Python layer's subclasses
    of :class:`gi.SettingError` (``ValueError``/``KeyError`` too, for older callers) as
    ``gi.SettingError``, not ``gi._checks.SettingValueError``."""
    from gi import _checks

    public = (GiError, SceneError, SettingError, GpuError, InternalError, OutOfMemoryError)
    for cls in (*public, RenderCancelled, RenderWarning, OutputError, AssetWarning, SceneWarning):
        cls.__module__ = "gi"
    for cls in (_checks.SettingValueError, _checks.AovError):
        cls.__module__ = "gi"
        cls.__qualname__ = "SettingError"


_present_as_gi()

__all__ = [
    "DEFAULT_METHOD",
    "AssetWarning",
    "GiError",
    "GpuError",
    "InternalError",
    "OutOfMemoryError",
    "OutputError",
    "RenderCancelled",
    "RenderResult",
    "Renderer",
    "RenderStats",
    "RenderWarning",
    "Scene",
    "SceneError",
    "SceneWarning",
    "SettingError",
    "__version__",
    "adapter_report",
    "animation_updates",
    "builtin_json",
    "builtin_scenes",
    "denoise",
    "footprint_radii",
    "gpu_counters",
    "load_scene",
    "method_options",
    "methods",
    "options_table",
    "read_channels",
    "read_image",
    "render",
    "render_animation",
    "render_batch",
    "save_image",
    "save_layers",
    "save_result",
    "to_display",
    "view",
]
