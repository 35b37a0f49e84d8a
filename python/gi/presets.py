"""Settings gi picks per method where the user gives none: the small passes of progressive
renders (``gi render --time``/``--passes``, the viewer's refinement of a still view) and the
viewer's interactive frames. Options a user gives always win; an option a method does not
take is left out for it."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

#: A progressive pass: small passes converge fastest for the time (docs/bench/progressive.md):
#: one camera sample per pixel, 30k photons for gather, 80k for ispm at full resolution (its
#: upsampling is a bias no pass removes).
PROGRESSIVE_PASS: dict[str, dict[str, Any]] = {
    "path": {"spp": 1},
    "gather": {"spp": 1, "photons": 30_000},
    "ispm": {"spp": 1, "photons": 80_000, "subsample": 1},
}


@dataclass(frozen=True)
class Interactive:
    """The viewer's frames while the view changes: ``options`` where the user gave none, on
    a frame of 1/``scale`` of the view's pixels a side (the page scales it up)."""

    scale: int = 1
    options: dict[str, Any] = field(default_factory=dict)

    def size(self, width: int, height: int) -> tuple[int, int]:
        """The frame size for a view of ``width`` × ``height``."""
        return max(1, math.ceil(width / self.scale)), max(1, math.ceil(height / self.scale))


#: Per method, chosen for a first frame within 1-2 s at 320×240 on lavapipe (2 cores):
#: the CPU methods at half the view's sides and one sample per pixel (gather and photon
#: with 10k photons a frame), ispm with 20k photons and 4 edge samples, bidir at half size
#: with 4 ray bundles of 64² and 16 VPLs a light with 64² shadow maps (2.0 s a camera move
#: on cornell-glass at 160×120 against 3.1 s with 8 bundles of 128², 32 VPLs of 128²,
#: 4 spp). docs/bench/view.md has the times.
INTERACTIVE: dict[str, Interactive] = {
    "path": Interactive(2, {"spp": 1}),
    "photon": Interactive(2, {"spp": 1, "photons": 10_000}),
    "gather": Interactive(2, {"spp": 1, "photons": 10_000}),
    "direct": Interactive(1, {"spp": 4}),
    "ispm": Interactive(1, {"spp": 4, "photons": 20_000}),
    "bidir": Interactive(
        2,
        {
            "spp": 1,
            "bundles": 4,
            "bundle_resolution": 64,
            "vpls_per_light": 16,
            "vpl_shadow_map_size": 64,
        },
    ),
}


def with_preset(preset: dict[str, Any], given: dict[str, Any]) -> dict[str, Any]:
    """``given`` over ``preset``: the options a user gave win."""
    return {**preset, **given}


def describe(options: dict[str, Any]) -> str:
    """The per-frame settings that set a frame's cost, in words (``1 spp, 10000 photons``)."""
    parts = []
    if "spp" in options:
        parts.append(f"{options['spp']} spp")
    if "photons" in options:
        parts.append(f"{options['photons']} photons")
    if options.get("subsample", 1) != 1:
        parts.append(f"subsample {options['subsample']}")
    return ", ".join(parts)
