"""`path`'s light vertices (option `light_vertices`, issue 29): the option reaches the
renderer, changes the noise and not the image's mean. The estimator itself (block by block
against BSDF sampling, and its lower noise) is tested in `crates/core/tests/light_vertex.rs`."""

import numpy as np

import gi


def test_light_vertices_change_the_noise_not_the_mean():
    scene = gi.load_scene("cornell")

    def render(on: bool, seed: int) -> np.ndarray:
        r = gi.render(scene, "path", size=(32, 32), spp=64, seed=seed, light_vertices=on)
        return np.asarray(r.radiance, np.float64)

    on, off = render(True, 1), render(False, 1)
    assert not np.array_equal(on, off)
    # Image means at 64 spp: 0.4961 (on) and 0.4969 (off) for seed 1; their standard errors
    # are about 0.2%, so 1.5% is far outside the noise but a connection counted twice
    # (+10-20% on this box) is not.
    assert abs(on.mean() / off.mean() - 1.0) < 0.015, (on.mean(), off.mean())
    # Noise: half the mean squared difference of two seeds, relative (as relMSE); measured
    # 0.36x with light vertices in this box (seeds 2 and 3).
    noise = {
        v: np.mean((render(v, 2) - render(v, 3)) ** 2 / (2 * (off**2 + 0.01)))
        for v in (True, False)
    }
    assert noise[True] < 0.6 * noise[False], noise
