"""Names of the images a render returns, per method, known before rendering."""

from __future__ import annotations

BASE = ("radiance", "albedo", "normal", "position", "depth", "caustics")

# Each method's own images (``RenderResult.extra``), in the order the renderer returns them.
METHOD_EXTRA: dict[str, tuple[str, ...]] = {
    "path": (),
    "photon": (),
    "gather": (),
    "direct": ("direct",),
    "ispm": ("direct", "specular", "indirect", "photons"),
    "bidir": ("direct", "specular", "indirect"),
}

# Added by ``denoise=True``: the radiance before denoising.
DENOISE_EXTRA = ("noisy",)


def aov_names(method: str, denoise: bool = False) -> list[str]:
    """The AOV names a render with ``method`` returns (``RenderResult.aov_names()``)."""
    extra = METHOD_EXTRA.get(method, ())
    return [*BASE, *extra, *(DENOISE_EXTRA if denoise else ())]


def check_aovs(method: str, names: list[str] | tuple[str, ...], denoise: bool = False) -> None:
    """Raises ``ValueError`` naming the first AOV that ``method`` does not produce."""
    known = aov_names(method, denoise)
    for name in names:
        if name not in known:
            raise ValueError(
                f"method {method!r} has no AOV {name!r} (available: {', '.join(known)})"
            )
