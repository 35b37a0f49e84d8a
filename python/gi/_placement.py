"""The checks the core makes of a ``matrix`` transform (``scene::matrix_from_rows``), made
by the importers before they hand placements over, so that an error names the glTF node or
the Mitsuba element instead of the generated object."""

from __future__ import annotations

import numpy as np


def first_bad_placement(m: np.ndarray) -> tuple[int, str] | None:
    """For affine matrices ``m`` (n, 4, 4): the index of the first matrix that fails the
    first check some matrix fails, and what that check says of it (``"the transform "`` is
    the caller's to put before it); ``None`` when all pass. Checks, in order: finite,
    translation within ±100000 m, each axis's scale in [1e-6, 1e6], invertible (|det| at
    least 1e-6 of the product of the axes' scales)."""
    with np.errstate(all="ignore"):
        finite = np.isfinite(m).all(axis=(1, 2))
        lin = np.where(finite[:, None, None], m[:, :3, :3], 0.0)
        lengths = np.linalg.norm(lin, axis=1)
        checks = (
            (~finite, "is not finite"),
            ((np.abs(m[:, :3, 3]) > 1e5).any(axis=1), "moves beyond ±100000 m"),
            (
                (lengths.min(axis=1) < 1e-6) | (lengths.max(axis=1) > 1e6),
                "scales an axis by less than 1e-6 or more than 1e6",
            ),
            (~(np.abs(np.linalg.det(lin)) >= 1e-6 * lengths.prod(axis=1)), "is singular"),
        )
    for bad, says in checks:
        if bad.any():
            return int(np.argmax(bad)), says
    return None
