"""The glossy (GGX) reflection of the sky in every method: a convex glossy object under a
constant sky of radiance L has outgoing radiance L·albedo(μ) exactly (no indirect light,
no shadow), which `path` renders without bias (next-event estimation and BSDF sampling by
multiple importance sampling). The other methods lost most of it (GLOSSY_GAP in
test_gltf_corpus.py): light sampling blind to the lobe (`gather`), photons as the only
estimate of the sky's direct light (`photon`), 16 sky directions for the whole frame (the
GPU direct light of `direct` and `ispm`). Measured before the fix on this scene (object's
interior mean against `path`; docs/bench/glossy-sky.md): roughness 0.1: photon +34%,
gather −91%, direct and ispm −73%; roughness 0.3: photon −4.7%, gather +6.4%, direct and
ispm +5.0%; roughness 0.001 (the glossy clamp of roughness maps): direct and ispm −100%
(the G-buffer's 16-bit roughness read back as a mirror); after: within 0.5%.

Tolerance 3% of the object's mean (the issue's 5% bound for the methods against `path`,
narrowed: `path`'s standard error here is about 0.3%, the methods' measured gaps under
0.5%)."""

import json
import warnings

import numpy as np
import pytest

import gi

SKY = 1.0


def glossy_sphere(tmp_path, roughness):
    desc = {
        "camera": {
            "position": [0, 0, 4],
            "look_at": [0, 0, 0],
            "fov": 40,
            "width": 24,
            "height": 24,
        },
        "materials": {
            "metal": {
                "diffuse": [0, 0, 0],
                "specular": [0.9, 0.9, 0.9],
                "roughness": roughness,
            }
        },
        # Flat facets: a convex polyhedron (no ray from its surface meets it again).
        "objects": [
            {"shape": {"type": "sphere", "radius": 1.0}, "material": "metal", "smooth": False}
        ],
        "environment": {"radiance": [SKY] * 3},
    }
    path = tmp_path / "glossy_sphere.json"
    path.write_text(json.dumps(desc))
    return gi.load_scene(path)


def interior(mask):
    m = mask.copy()
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            m &= np.roll(np.roll(mask, dy, 0), dx, 1)
    m[[0, -1], :] = False
    m[:, [0, -1]] = False
    return m


SETTINGS = {
    "photon": {"spp": 16, "photons": 200_000},
    "gather": {"spp": 16, "photons": 200_000},
    "direct": {"spp": 4},
    "ispm": {"spp": 4, "photons": 20_000},
    # Issue 47: bidir.wgsl summed the sky's glossy light over its 16 bundle directions
    # (object's mean against `path`, seeds 1–3: 0.00 at roughness 0.001, 0.49–0.50 at 0.1
    # and 0.3); with env_glossy.wgsl's quadrature 0.999–1.003.
    "bidir": {"spp": 4},
}


@pytest.mark.parametrize("roughness", [0.001, 0.1, 0.3])
@pytest.mark.parametrize("method", sorted(SETTINGS))
def test_glossy_sphere_under_a_constant_sky_matches_path(tmp_path, method, roughness):
    scene = glossy_sphere(tmp_path, roughness)
    ref = gi.render(scene, "path", spp=64, seed=1)
    obj = interior(ref.depth > 0)
    assert obj.sum() > 150
    expected = ref.radiance[obj].mean()
    # L·albedo: about L·F0 (0.9; single-scattering GGX loses a little), far above the
    # diffuse-only answer (0).
    assert 0.85 < expected < 0.91
    with warnings.catch_warnings():
        # `ispm` may say that its photons carry no indirect light here.
        warnings.simplefilter("ignore", gi.RenderWarning)
        got = gi.render(scene, method, seed=2, **SETTINGS[method]).radiance[obj].mean()
    assert got == pytest.approx(expected, rel=0.03)
