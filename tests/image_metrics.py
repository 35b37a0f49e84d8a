"""Image error measures shared by the tests and the scripts (pytest puts this folder on the
tests' path; ``scripts/shared.py`` on the scripts'): one definition of the FLIP every table
and bound is measured with."""

import numpy as np


def flip(reference: np.ndarray, test: np.ndarray) -> float:
    """Mean HDR-FLIP (flip-evaluator, 67 pixels per degree); 0 is identical. Negative
    values of ``test`` are clipped."""
    import flip_evaluator  # here: scripts that only render Mitsuba's side need not have it

    _, mean, _ = flip_evaluator.evaluate(
        np.ascontiguousarray(reference, np.float32),
        np.ascontiguousarray(np.maximum(test, 0.0), np.float32),
        "HDR",
        applyMagma=False,
    )
    return float(mean)
