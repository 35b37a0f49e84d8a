"""Every error a user can cause through gi.render, gi.Renderer (constructor, update, resize,
render, render_progressive, describe), gi.save_image / gi.save_result and the `gi` command is
a gi.GiError whose message names the option or field: hypothesis drives each entry point
with random arguments (wrong types, extremes, unknown names, valid values) and any other
exception fails the test.

Valid arguments are kept cheap (8x8 images, few photons), so that the examples that render
take well under a second; the whole file runs in about a minute on two cores. Set
GI_PROPERTY_EXAMPLES to run more examples per test (a longer search).
"""

from __future__ import annotations

import argparse
import contextlib
import inspect
import io
import os
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import gi
from gi import cli

os.environ.setdefault("GI_ADAPTER", "cpu")

EXAMPLES = int(os.environ.get("GI_PROPERTY_EXAMPLES", "0"))


def examples(n: int) -> settings:
    return settings(
        max_examples=EXAMPLES or n,
        deadline=None,
        derandomize=not EXAMPLES,
        suppress_health_check=list(HealthCheck),
        database=None,
    )


def mostly(good: st.SearchStrategy[Any], bad: st.SearchStrategy[Any]) -> st.SearchStrategy[Any]:
    """``good`` three times in four, else ``bad`` (``good | bad`` would weigh each branch of
    a ``one_of`` alike, and ``bad`` has many)."""
    return st.sampled_from([good, good, good, bad]).flatmap(lambda s: s)


#: Values of any kind: small integers (valid or one off), integers beyond every setting's
#: type, floats of all kinds, strings, containers, objects. No large valid values: a render
#: stays cheap (huge photon counts or sizes are valid and would take minutes).
ANY = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(-3, 6),
    st.sampled_from([-(2**64), -1, 2**64, 10**30]),
    st.floats(max_value=1e3) | st.just(float("inf")),
    st.sampled_from([float("nan"), -1e308, 1e-320, np.float32(np.nan), np.int64(-5)]),
    st.text(max_size=4),
    st.lists(st.integers(-2, 2), max_size=4),
    st.tuples(st.integers(-2, 12), st.integers(-2, 12)),
    st.just(object()),
    st.just(np.array([1.0, np.nan, 2.0])),
    st.dictionaries(st.text(max_size=3), st.integers(-1, 2), max_size=2),
)

#: The keywords of gi.render: its own and the render options (the core's table), and a few
#: names it does not know.
RENDER_KEYWORDS = [
    n for n, p in inspect.signature(gi.render).parameters.items() if p.kind == p.KEYWORD_ONLY
] + sorted({row["name"] for row in gi.options_table()} | {"size"})
NAMES = st.sampled_from(RENDER_KEYWORDS) | st.sampled_from(["sp", "colour", "temporal_frames"])
METHODS = st.sampled_from(gi.methods()) | st.sampled_from(["nope", "", 3, None])

#: Cheap settings for every method, overridden by the random ones.
CHEAP: dict[str, Any] = {
    "size": (8, 8),
    "spp": 1,
    "photons": 300,
    "max_depth": 3,
    "shadow_map_size": 16,
    "rsm_size": 4,
    "vpls_per_light": 2,
    "vpl_shadow_map_size": 16,
    "bundles": 2,
    "bundle_resolution": 16,
    "bundle_memory_mb": 1,
}


@pytest.fixture(scope="module")
def cornell() -> gi.Scene:
    return gi.load_scene("cornell")


def typed(call: Any, *args: Any, **kwargs: Any) -> Any:
    """Runs the call: it may succeed or raise a gi.GiError; anything else propagates and
    fails the test. gi's warnings (options a method ignores, a scene that renders black)
    are expected here; any other warning is an error, as pytest makes it."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gi.RenderWarning)
        warnings.simplefilter("ignore", gi.SceneWarning)
        try:
            return call(*args, **kwargs)
        except gi.GiError as e:
            assert str(e), type(e)
            return None


@examples(150)
@given(
    scene=st.sampled_from(["cached", "cached", "cached", "cornell", "no-such-scene", 5, None]),
    method=METHODS,
    overrides=st.dictionaries(NAMES, mostly(st.integers(0, 4) | st.booleans(), ANY), max_size=3),
    denoise=st.sampled_from([False, False, True, "yes"]),
)
def test_render_raises_only_typed_errors(cornell, scene, method, overrides, denoise):
    target = cornell if scene == "cached" else scene
    kwargs = {**CHEAP, "denoise": denoise, **overrides}
    typed(gi.render, target, method, **kwargs)


def field_values() -> st.SearchStrategy[Any]:
    """Scene-format fields, valid and not."""
    vec = st.lists(mostly(st.floats(-1, 1), ANY), min_size=3, max_size=3)
    return st.dictionaries(
        st.sampled_from(
            ["position", "look_at", "up", "fov", "width", "height", "intensity", "type"]
            + ["direction", "inner_angle", "outer_angle", "translate", "rotate", "scale"]
            + ["matrix", "diffuse", "specular", "roughness", "diffuse_texture", "colour"]
        ),
        mostly(vec | st.floats(0, 1) | st.sampled_from(["point", "spot", "nope.png"]), ANY),
        max_size=3,
    )


#: Keys of the update dicts (hashable values of any kind).
KEYS = st.one_of(
    st.integers(-1, 8),
    st.sampled_from(["white", "red", "nope", None, True, 2**64, float("nan"), 1.0, (1, 2)]),
    st.text(max_size=3),
)
UPDATES = st.fixed_dictionaries(
    {},
    optional={
        "camera": mostly(field_values(), ANY),
        "lights": mostly(st.dictionaries(KEYS, mostly(field_values(), ANY), max_size=2), ANY),
        "objects": mostly(st.dictionaries(KEYS, mostly(field_values(), ANY), max_size=2), ANY),
        "materials": mostly(st.dictionaries(KEYS, mostly(field_values(), ANY), max_size=2), ANY),
    },
)
SIDES = mostly(st.integers(-2, 12), st.sampled_from([2**32, -(2**40), 16385]) | ANY)
PASSES = mostly(st.integers(1, 2), st.sampled_from([0, -2, -(2**64), None, "2", 1.5, True]))
SECONDS = mostly(
    st.sampled_from([None, 0.01]),
    st.sampled_from([0.0, -1.0, float("nan"), float("inf"), "1", True]),
)

OPERATIONS = st.one_of(
    st.tuples(st.just("update"), UPDATES),
    st.tuples(st.just("resize"), st.tuples(SIDES, SIDES)),
    st.tuples(
        st.just("render"),
        st.fixed_dictionaries(
            {},
            optional={
                "aovs": mostly(st.booleans(), ANY),
                "extras": mostly(st.booleans(), ANY),
                "seed": mostly(st.integers(0, 2**64 - 1), ANY),
                "progress": mostly(st.booleans(), ANY),
            },
        ),
    ),
    st.tuples(
        st.just("render_progressive"),
        st.fixed_dictionaries(
            {},
            optional={
                "passes": PASSES,
                "seconds": SECONDS,
                "aovs": mostly(st.booleans(), ANY),
                "on_pass": mostly(st.none(), ANY),
                "progress": mostly(st.booleans(), ANY),
            },
        ),
    ),
    st.tuples(
        st.just("describe"),
        mostly(
            st.sampled_from([("camera", None), ("light", 0), ("object", 6), ("material", "red")]),
            st.tuples(st.sampled_from(["camera", "light", "object", "material"]) | ANY, KEYS),
        ),
    ),
)


@examples(200)
@given(
    method=st.sampled_from(["path", "gather", "direct"]),
    progressive=st.booleans(),
    ctor=st.dictionaries(NAMES, ANY, max_size=2),
    operations=st.lists(OPERATIONS, min_size=1, max_size=4),
)
def test_renderer_raises_only_typed_errors(cornell, method, progressive, ctor, operations):
    cheap = gi.method_options(method, **CHEAP)
    r = typed(gi.Renderer, cornell, method, **{**cheap, "progressive": progressive, **ctor})
    if r is None:
        r = gi.Renderer(cornell, method, progressive=progressive, **cheap)
    for name, args in operations:
        if name == "update":
            typed(r.update, **args)
        elif name == "resize":
            typed(r.resize, *args)
        elif name == "describe":
            typed(r.describe, *args)
        else:
            typed(getattr(r, name), **args)
        # The renderer stays usable after any of them.
        assert r.size[0] >= 1 and r.size[1] >= 1


SUFFIXES = [".exr", ".png", ".hdr", ".pfm", ".jpg", ".tif", ".xyz", "", ".EXR"]
ARRAYS = mostly(
    st.tuples(
        st.lists(st.integers(1, 5), min_size=2, max_size=3),
        st.sampled_from(["float32", "float64", "int32", "bool"]),
    ).map(lambda s: np.ones(s[0], dtype=s[1])),
    st.tuples(
        st.lists(st.integers(0, 5), min_size=0, max_size=4),
        st.sampled_from(["float32", "complex64", "object", "U2"]),
    ).map(lambda s: np.ones(s[0], dtype=s[1]))
    | st.sampled_from([np.full((3, 2, 3), np.inf, np.float32), np.full((2, 2), 1e300)])
    | ANY,
)


def paths(base: Path) -> st.SearchStrategy[Any]:
    return mostly(
        st.tuples(st.sampled_from(["a", "sub/b", "dir", "%d"]), st.sampled_from(SUFFIXES)).map(
            lambda t: base / f"{t[0]}{t[1]}"
        ),
        st.sampled_from(["/proc/x.png", base / "a\0.exr", base / "file.png" / "x.exr"]) | ANY,
    )


@pytest.fixture(scope="module")
def results(cornell) -> dict[str, gi.RenderResult]:
    full = gi.render(cornell, "direct", **gi.method_options("direct", **CHEAP))
    bare = gi.Renderer(cornell, "path", **gi.method_options("path", **CHEAP)).render()
    return {"full": full, "bare": bare}


@examples(150)
@given(data=st.data())
def test_image_output_raises_only_typed_errors(tmp_path_factory, results, data):
    base = tmp_path_factory.mktemp("out")
    (base / "dir.exr").mkdir()
    (base / "file.png").write_text("x")
    path = data.draw(paths(base))
    exposure = data.draw(mostly(st.floats(-70, 70), ANY))
    tonemap = data.draw(mostly(st.sampled_from(["clip", "filmic", "aces"]), ANY))
    if data.draw(st.booleans()):
        typed(gi.save_image, path, data.draw(ARRAYS), exposure=exposure, tonemap=tonemap)
    else:
        result = data.draw(mostly(st.sampled_from(list(results.values())), ANY))
        names = ["albedo", "depth", "normal", "direct", "caustics", "noisy", "nope", "radiance"]
        aovs = data.draw(mostly(st.lists(st.sampled_from(names), max_size=3), ANY))
        typed(gi.save_result, path, result, aovs, tonemap=tonemap, exposure=exposure)


def render_flags() -> list[argparse.Action]:
    """The options of `gi render`, from its parser."""
    sub = next(a for a in cli._parser()._actions if isinstance(a, argparse._SubParsersAction))
    render = sub.choices["render"]
    return [a for a in render._actions if a.option_strings and a.dest not in ("help", "output")]


#: Any flag's value: numbers of all kinds, names, junk.
FLAG_VALUES = st.sampled_from(
    ["-1", "0", "1", "2", "8x8", "0:2", "3:1", "nan", "inf", "1e30", "x", "", "auto"]
    + ["cone", "all", "albedo", "depth", "caustics", "noisy", "filmic", "path", "cpu"]
    + ["99999999999999999999", "0.05"]
)


def flag_value(action: argparse.Action) -> st.SearchStrategy[str]:
    """Mostly a value of the flag's own kind (cheap ones: at most a second of passes or a
    few frames), else any value."""
    kinds: dict[Any, list[str]] = {
        int: ["0", "1", "2", "3"],
        float: ["0", "0.5", "1", "2"],
        cli._size: ["8x8", "7x5"],
        cli._frames: ["0:2", "1", "0:3:2"],
        cli._fps: ["0.05", "0.3", "1"],
    }
    if action.choices:
        good = list(action.choices)
    elif action.type in kinds:
        good = kinds[action.type]
    else:  # --method, --adapter, --aov
        good = [*gi.methods(), "cpu", "albedo", "depth", "all", "direct"]
    return mostly(st.sampled_from(good), FLAG_VALUES)


@examples(80)
@given(data=st.data())
def test_cli_raises_only_typed_errors(tmp_path_factory, data):
    base = tmp_path_factory.mktemp("cli")
    flags = render_flags()
    scene = data.draw(mostly(st.sampled_from(["cornell", "cornell-anim"]), st.just("nope")))
    name = data.draw(mostly(st.sampled_from(["x", "f_%03d"]), st.sampled_from(["%d_%d", "y%"])))
    suffix = data.draw(mostly(st.sampled_from([".exr", ".png", ".hdr", ".mp4"]), st.just(".xyz")))
    argv = ["render", scene, "-o", str(base / f"{name}{suffix}"), "--size", "8x8"]
    argv += ["--spp", "1", "--photons", "300", "-q"]
    if data.draw(st.booleans()):
        argv += ["--frames", "0:2"]
    for action in data.draw(st.lists(st.sampled_from(flags), max_size=4)):
        argv.append(data.draw(st.sampled_from(action.option_strings)))
        if action.nargs != 0:
            argv.append(data.draw(flag_value(action)))
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            args = cli._parser().parse_args(argv)
        except SystemExit as e:  # argparse's own message: a usage line and the error
            assert e.code == 2 and "error:" in err.getvalue(), (argv, err.getvalue())
            return
        assert typed(cli.run, args) in (0, None), argv
