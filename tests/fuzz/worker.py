"""Runs one group of fuzz cases in this process and logs each case as JSON lines.

    python tests/fuzz/worker.py --group scenes --seed 1 --cases 100 --log out.jsonl

Before a case runs, a ``start`` record (with the generated input) is written and flushed;
after it, an ``end`` record with its outcome: ``ok`` (rendered, every pixel finite),
``typed`` (a ``gi.GiError``), ``untyped`` (any other exception) or ``nan`` (accepted but a
non-finite pixel). A crash or a hang shows as a ``start`` with no ``end``; the driver
(``scripts/ci/fuzz.py``) watches for both.
"""

from __future__ import annotations

import argparse
import itertools
import json
import os
import shutil
import sys
import tempfile
import time
import traceback
from pathlib import Path
from typing import Any

os.environ.setdefault("GI_ADAPTER", "cpu")
sys.path.insert(0, str(Path(__file__).resolve().parent))

import numpy as np  # noqa: E402
import strategies as fz  # noqa: E402
from hypothesis import HealthCheck, Phase, given, seed, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

import gi  # noqa: E402

#: Cheap settings for the renders of scene and mesh cases.
SMALL = {"size": (8, 8), "spp": 1, "photons": 400, "max_depth": 8, "shadow_map_size": 32}

MESH_SCENE = {
    "camera": {"position": [0, 0, 4], "look_at": [0, 0, 0], "width": 8, "height": 8},
    "lights": [{"type": "point", "position": [0, 2, 3], "intensity": [5, 5, 5]}],
    "materials": {
        "m": {"diffuse": [0.6, 0.6, 0.6]},
        "g": {"diffuse": [0, 0, 0], "transmission": [1, 1, 1]},
    },
}


class Log:
    def __init__(self, path: Path) -> None:
        self.file = path.open("a", encoding="utf-8")
        self.counter = itertools.count()

    def write(self, record: dict[str, Any]) -> None:
        self.file.write(json.dumps(record, default=repr) + "\n")
        self.file.flush()


def finite_result(result: gi.RenderResult) -> str | None:
    """The name of the first image with a non-finite pixel, or None."""
    for name in result.aov_names():
        if not np.isfinite(result.aov(name)).all():
            return name
    return None


def outcome(fn: Any) -> tuple[str, str]:
    """Runs `fn`; (status, detail)."""
    try:
        bad = fn()
    except gi.GiError as e:
        return "typed", f"{type(e).__name__}: {str(e)[:200]}"
    except Exception as e:  # anything else is what the fuzzer looks for
        tb = traceback.format_exc().splitlines()[-6:]
        return "untyped", f"{type(e).__name__}: {str(e)[:300]} | " + " / ".join(tb)
    if bad:
        return "nan", bad
    return "ok", ""


def render_all(scene: gi.Scene, methods: list[str]) -> str | None:
    for method in methods:
        bad = finite_result(gi.render(scene, method, **SMALL))
        if bad:
            return f"{method}: {bad}"
    return None


def run_case(log: Log, group: str, data: dict[str, Any], fn: Any) -> None:
    case = next(log.counter)
    log.write({"event": "start", "case": case, "group": group, "input": data, "t": time.time()})
    t, cpu = time.monotonic(), time.process_time()
    status, detail = outcome(fn)
    log.write(
        {
            "event": "end",
            "case": case,
            "group": group,
            "status": status,
            "detail": detail,
            "seconds": round(time.monotonic() - t, 3),
            # CPU time of all threads: tells a slow case from one starved by other load.
            "cpu_seconds": round(time.process_time() - cpu, 3),
        }
    )


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("--group", choices=["scenes", "meshes", "settings"], required=True)
    p.add_argument("--seed", type=int, required=True)
    p.add_argument("--cases", type=int, required=True)
    p.add_argument("--log", type=Path, required=True)
    p.add_argument("--all-methods", action="store_true", help="render each case with all five")
    args = p.parse_args()
    log = Log(args.log)
    workdir = Path(tempfile.mkdtemp(prefix="gi-fuzz-"))
    methods_cycle = itertools.cycle(fz.METHODS)

    def methods() -> list[str]:
        return list(fz.METHODS) if args.all_methods else [next(methods_cycle)]

    config = settings(
        max_examples=args.cases,
        phases=[Phase.generate],
        database=None,
        deadline=None,
        suppress_health_check=list(HealthCheck),
    )

    if args.group == "scenes":

        @seed(args.seed)
        @config
        @given(fz.scene_text())
        def scenes(text: str) -> None:
            path = workdir / "scene.json"
            path.write_text(text, encoding="utf-8", errors="surrogatepass")
            ms = methods()
            run_case(
                log,
                "scenes",
                {"scene": text[:4000], "methods": ms},
                lambda: render_all(gi.load_scene(path), ms),
            )

        scenes()
    elif args.group == "meshes":

        @seed(args.seed)
        @config
        @given(st.data())
        def meshes(data: st.DataObject) -> None:
            mesh = data.draw(fz.mesh_file(workdir))
            obj: dict[str, Any] = {
                "shape": {"type": "mesh", "file": mesh.name},
                "material": data.draw(st.sampled_from(["m", "g"])),
            }
            if data.draw(st.booleans()):
                obj["transform"] = data.draw(fz.transform(data.draw(st.sampled_from(fz.BAD_RATES))))
            desc = dict(MESH_SCENE, objects=[obj])
            path = workdir / "scene.json"
            path.write_text(json.dumps(desc))
            ms = methods()
            blob = mesh.read_bytes()
            shown = blob[:2000].decode("latin-1")
            # A GLB is sometimes loaded as a whole scene (its nodes as instances).
            whole = mesh.suffix == ".glb" and data.draw(st.booleans())
            run_case(
                log,
                "meshes",
                {
                    "mesh": mesh.name,
                    "bytes": len(blob),
                    "head": shown,
                    "object": "(the file as a scene)" if whole else obj,
                    "methods": ms,
                },
                lambda: render_all(gi.load_scene(mesh if whole else path), ms),
            )

        meshes()
    else:
        scene = gi.load_scene("cornell-glass")

        @seed(args.seed)
        @config
        @given(fz.render_settings(), fz.number(-10.0, 10.0))
        def settings_case(kwargs: dict[str, Any], exposure: float) -> None:
            def go() -> str | None:
                result = gi.render(scene, **kwargs)
                gi.save_image(workdir / "out.png", result.radiance, exposure=exposure)
                return finite_result(result)

            run_case(log, "settings", {"settings": kwargs, "exposure": exposure}, go)

        settings_case()
    shutil.rmtree(workdir, ignore_errors=True)


if __name__ == "__main__":
    main()
