"""Issue 44 item 3, cost: `ispm`'s sky pilot (photon/sky_pilot.rs: the batch of plain sky
photons whose stored paths the aimed photons of photon/sky_guide.rs are drawn around) is
traced once and kept while the geometry, the materials and the sky stay as they were; a
frame that keeps it reports the stage ``sky pilot`` at 0. After a change the pilot is traced
again with its fixed seed, so the frame is the frame of a new renderer of the changed scene
(its Rust unit tests compare the pilots themselves)."""

from pathlib import Path

import numpy as np

import gi

SCENE = Path(__file__).parent / "scenes" / "openings" / "window_room.json"
OPTS = {"photons": 20000, "temporal_frames": 1, "seed": 1}
SKY = {"source": np.full((4, 8, 3), 3.0, np.float32), "mode": "replace"}


def pilot_seconds(frame) -> float:
    return dict(frame.stats.stages)["sky pilot"]


def test_sky_pilot_is_kept_until_geometry_or_sky_change():
    scene = gi.load_scene(SCENE)
    r = gi.Renderer(scene, "ispm", **OPTS)
    assert pilot_seconds(r.render()) > 0
    # Another seed: every photon traced anew, the pilot kept.
    again = r.render(seed=2)
    assert dict(again.stats.stages)["cpu trace"] > 0
    assert pilot_seconds(again) == 0
    assert pilot_seconds(r.render(seed=3)) == 0
    # The window's right-hand jamb moved into the room: traced again, as a new renderer does.
    r.update(objects={8: {"translate": [1.5, 1.4, 1.35]}})
    moved = r.render(seed=4)
    assert pilot_seconds(moved) > 0
    assert pilot_seconds(r.render(seed=5)) == 0
    fresh_scene = gi.load_scene(SCENE)
    fresh = gi.Renderer(fresh_scene, "ispm", **OPTS)
    fresh.update(objects={8: {"translate": [1.5, 1.4, 1.35]}})
    np.testing.assert_allclose(moved.radiance, fresh.render(seed=4).radiance, rtol=0, atol=1e-6)
    # Another sky: traced again.
    r.update(environment=SKY)
    assert pilot_seconds(r.render(seed=6)) > 0
    assert pilot_seconds(r.render(seed=7)) == 0


def test_cornell_has_no_sky_pilot():
    out = gi.render("cornell", "ispm", size=(32, 24), photons=2000, seed=1)
    assert "sky pilot" not in dict(out.stats.stages)
