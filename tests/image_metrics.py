"""Image error measures shared by the tests."""

import flip_evaluator
import numpy as np


def flip(reference: np.ndarray, test: np.ndarray) -> float:
    """Mean HDR-FLIP (flip-evaluator, 67 pixels per degree); 0 is identical."""
    _, mean, _ = flip_evaluator.evaluate(
        np.ascontiguousarray(reference, np.float32),
        np.ascontiguousarray(np.maximum(test, 0.0), np.float32),
        "HDR",
        applyMagma=False,
    )
    return float(mean)
