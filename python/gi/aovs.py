"""Names of the images a render returns, per method, known before rendering."""

from __future__ import annotations

from gi._checks import named_error

BASE = ("radiance", "albedo", "normal", "position", "depth", "caustics")

#: Methods with an image of their own for the caustic paths (light → mirror/glass → diffuse
#: → eye) in ``caustics``; the others have their caustic light in the radiance only.
CAUSTICS_METHODS = ("path",)

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


def base_names(method: str) -> list[str]:
    """The images of :attr:`BASE` that ``method`` renders (``caustics`` only where it has
    them apart)."""
    return [n for n in BASE if n != "caustics" or method in CAUSTICS_METHODS]


def aov_names(method: str, denoise: bool = False) -> list[str]:
    """The AOV names a render with ``method`` returns (``RenderResult.aov_names()``)."""
    extra = METHOD_EXTRA.get(method, ())
    return [*base_names(method), *extra, *(DENOISE_EXTRA if denoise else ())]


def why_not(method: str, name: str, denoise: bool = False) -> str:
    """Why a render with ``method`` has no AOV ``name``, and the AOVs it has."""
    known = ", ".join(aov_names(method, denoise))
    if name == "caustics" and method not in CAUSTICS_METHODS:
        only = ", ".join(CAUSTICS_METHODS)
        return (
            f"method {method!r} has no AOV 'caustics': its caustic light is part of the"
            f" radiance; method {only} renders it apart (available: {known})"
        )
    if name in DENOISE_EXTRA and not denoise:
        return f"AOV {name!r} is the radiance before denoising: it needs --denoise (denoise=True)"
    return f"method {method!r} has no AOV {name!r} (available: {known})"


def check_aovs(method: str, names: list[str] | tuple[str, ...], denoise: bool = False) -> None:
    """Raises :class:`gi.SettingError` (also a ``ValueError``; setting ``aov``) naming the
    first AOV that ``method`` does not produce and the AOVs it does."""
    known = aov_names(method, denoise)
    for name in names:
        if not isinstance(name, str):
            raise named_error("aov", f"AOV names are strings, got {name!r} (available: {known})")
        if name not in known:
            raise named_error("aov", why_not(method, name, denoise))
