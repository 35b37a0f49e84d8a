"""No silent omissions (issue 29): a method asked for light transport it does not compute, or
given an option it ignores, says so with a `gi.RenderWarning` naming it; a method that
computes everything it is asked for says nothing."""

import json
import warnings

import pytest

import gi

SMALL = {"size": (8, 8), "spp": 1, "photons": 2000}


def quiet(scene: gi.Scene, method: str, **options) -> gi.Renderer:
    """A renderer made with every warning an error."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return gi.Renderer(scene, method, **gi.method_options(method, **SMALL, **options))


@pytest.mark.parametrize("method", gi.methods())
def test_point_lights_and_defaults_warn_of_nothing(method):
    """The built-in scenes' point lights and the defaults: every method computes what it is
    asked for."""
    quiet(gi.load_scene("cornell"), method)


@pytest.mark.parametrize("method", gi.methods())
def test_an_option_the_method_ignores_is_named(method):
    others = [
        row
        for row in gi.options_table()
        if method not in row["methods"]
        and row["name"] not in {r["name"] for r in gi.options_table(method)}
    ]
    assert others, method
    row = others[0]
    with pytest.warns(
        gi.RenderWarning, match=f"`{row['name']}` does not apply to method `{method}`"
    ):
        gi.Renderer(gi.load_scene("cornell"), method, **{row["name"]: row["default"]})


def test_bidir_computes_every_depth_and_the_caustics_of_every_light():
    """bidir computes any max_depth (its light subpaths, issue 29) and the paths through
    mirrors and glass (its CPU light tracers and camera paths): no warning at any depth nor on
    the built-in scenes with mirrors and glass, nor for a parallel sun's caustics seen
    directly (its delta-chain light tracer since issue 44, `tests/test_bidir_glass.py`;
    before, a warning named them)."""
    scene = gi.load_scene("cornell")
    for depth in (1, 3, 5, 64):
        quiet(scene, "bidir", max_depth=depth)
    for name in ("cornell-glass", "caustic-ring", "mirror-shadow", "ring-room"):
        quiet(gi.load_scene(name), "bidir")
    desc = json.loads(gi.builtin_json("cornell-glass"))
    desc["lights"] = [{"type": "directional", "direction": [0, -1, 0], "irradiance": [2, 2, 2]}]
    sun = gi.Scene.from_json(json.dumps(desc), "sun-glass")
    quiet(sun, "bidir")


def emitting_cornell() -> gi.Scene:
    desc = json.loads(gi.builtin_json("cornell"))
    desc["materials"]["lamp"] = {"diffuse": [0.5, 0.5, 0.5], "emission": [5, 5, 5]}
    desc["objects"][-1]["material"] = "lamp"
    return gi.Scene.from_json(json.dumps(desc), "emitting-cornell")


@pytest.mark.parametrize("method", gi.methods())
def test_area_lights_are_rendered_without_a_warning(method):
    """An emitting box: every method renders it without a word (`path`, `photon`, `gather`,
    `direct`, `ispm` since the lights foundation; `bidir` since its VPLs come from the
    emitters too, `frame/bidir/emitted.rs`)."""
    scene = emitting_cornell()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        r = gi.Renderer(scene, method, **gi.method_options(method, **SMALL))
    messages = [str(w.message) for w in caught if issubclass(w.category, gi.RenderWarning)]
    assert messages == []
    assert r.render().radiance.max() > 0
