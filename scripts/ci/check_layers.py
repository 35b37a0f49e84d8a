#!/usr/bin/env python3
"""Checks the core crate's layering (docs/architecture.md): every `crate::` path in
`crates/core/src` (test modules left out) must go from a top-level module to one below it in
LAYERS, so that no import runs upwards and no two modules import each other; and no
function may be longer than MAX_FN lines. Prints what it finds; exits 1 on a violation.

    scripts/ci/check_layers.py [SRC]        (default crates/core/src; run by `make test`)
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

# Top to bottom: a module may import only modules after it.
LAYERS = [
    "frame",  # the Renderer, options, one file per method
    "estimate",  # indirect-light estimators over one photon set (GPU and CPU)
    "raster",  # raster passes
    "gpu",  # device, pipeline cache, layout helpers, timer, *Raw structs, WGSL
    "photon",  # photon records, trace, maps, camera and specular paths
    "trace",  # BVH, path and light tracing
    "scene",  # scene model, lights, light views
    "bsdf",  # the uber BSDF
    "texture",
    "sampling",
    "image",
    "cancel",  # progress and cancellation
    "memory",  # memory checks
    "error",  # the error type
]
MAX_FN = 150

USE_GROUP = re.compile(r"use\s+crate::\{([^;]*)\};", re.S)
PATH = re.compile(r"crate::(\w+)")
TEST_MODULE = re.compile(r"#\[cfg\(test\)\]\s*(pub\s+)?mod\s+\w+\s*\{")
FN = re.compile(r"(\s*)(pub(\([^)]*\))?\s+)?(const\s+)?(async\s+)?(unsafe\s+)?fn\s+(\w+)")


def non_test_body(text: str) -> str:
    """The file up to its `#[cfg(test)] mod ... {` (test code may import anything)."""
    cut = TEST_MODULE.search(text)
    return text[: cut.start()] if cut else text


def imports(body: str) -> set[str]:
    found = set(PATH.findall(body))
    for group in USE_GROUP.finditer(body):
        for name in re.findall(r"(?:^|[,{\s])(\w+)(?=::|\s*[,}]|$)", group.group(1)):
            if name != "self" and name[0].islower():
                found.add(name)
    return found


def functions(rel: str, body: str) -> list[tuple[int, str]]:
    """(lines, "file:line name") of every function whose closing brace is at its indent."""
    out = []
    lines = body.split("\n")
    for i, line in enumerate(lines):
        m = FN.match(line)
        if not m or line.rstrip().endswith(";"):
            continue
        indent = m.group(1)
        for j in range(i + 1, len(lines)):
            if lines[j].startswith(indent + "}") and len(lines[j].strip()) == 1:
                out.append((j - i + 1, f"{rel}:{i + 1} {m.group(7)}"))
                break
    return out


def main() -> int:
    src = Path(sys.argv[1] if len(sys.argv) > 1 else "crates/core/src")
    rank = {name: i for i, name in enumerate(LAYERS)}
    problems: list[str] = []
    long: list[tuple[int, str]] = []
    edges: dict[str, set[str]] = {}
    for path in sorted(src.rglob("*.rs")):
        rel = path.relative_to(src).as_posix()
        top = rel.split("/")[0].removesuffix(".rs")
        body = non_test_body(path.read_text(encoding="utf-8"))
        long += functions(rel, body)
        if top in ("lib", "main"):
            continue
        if top not in rank:
            problems.append(f"{rel}: module `{top}` is not in LAYERS (scripts/ci/check_layers.py)")
            continue
        for target in imports(body) - {top}:
            if target not in rank:
                continue
            edges.setdefault(top, set()).add(target)
            if rank[target] < rank[top]:
                problems.append(f"{rel}: `{top}` imports `{target}`, a layer above it")
    long.sort(reverse=True)
    for n, where in long:
        if n > MAX_FN:
            problems.append(f"{where}: {n} lines (at most {MAX_FN})")
    for top in LAYERS:
        below = ", ".join(sorted(edges.get(top, ()), key=rank.get))
        print(f"{top:9} -> {below}")
    print(f"longest function: {long[0][0]} lines ({long[0][1]})" if long else "no functions")
    for p in problems:
        print(f"layer check: {p}")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
