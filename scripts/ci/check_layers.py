#!/usr/bin/env python3
"""Checks the core crate's layering (docs/architecture.md): every `crate::` path in
`crates/core/src` (test modules left out) must go from a top-level module to one below it in
LAYERS, so that no import runs upwards and no two modules import each other; no
function may be longer than MAX_FN lines; inside `frame/`, no method module (METHODS)
imports another method's module (what methods share lives in `frame/gpu/`,
`frame/options/` or a lower layer), no function allows `clippy::too_many_arguments` and
none takes a tuple parameter (pass a struct of what belongs together). Prints what it
finds; exits 1 on a violation.

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
# The method modules of `frame/`: none may import another.
METHODS = {"direct", "ispm", "bidir", "path", "photon", "gather"}

USE_GROUP = re.compile(r"use\s+crate::\{([^;]*)\};", re.S)
PATH = re.compile(r"crate::(\w+)")
TEST_MODULE = re.compile(r"#\[cfg\(test\)\]\s*(pub\s+)?mod\s+\w+\s*\{")
RELATIVE = re.compile(
    r"\b((?:crate|self|super)(?:::(?:self|super))*)((?:::\w+)*)(?:::(\{[^;]*?\}))?", re.S
)
FN_PARAMS = re.compile(r"\bfn\s+(\w+)\s*(?:<[^>{]*>)?\s*\(")
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


def module_path(rel: str) -> list[str]:
    """`frame/ispm/photons.rs` -> [frame, ispm, photons]; a `mod.rs` is its folder."""
    parts = rel.removesuffix(".rs").split("/")
    return parts[:-1] if parts[-1] == "mod" else parts


def resolved_paths(rel: str, body: str) -> set[tuple[str, ...]]:
    """The paths that `crate::`, `self::` and `super::` paths in `body` name (with each
    first name of a `{...}` group)."""
    here = module_path(rel)
    out = set()
    for m in RELATIVE.finditer(body):
        parts = m.group(1).split("::")
        base = [] if parts[0] == "crate" else list(here)
        for part in parts[1:] if parts[0] == "crate" else parts:
            if part == "super":
                base = base[:-1]
        base += [n for n in m.group(2).split("::") if n]
        group = m.group(3)
        names = re.findall(r"(?:^|[,{])\s*(\w+)", group) if group else []
        out.add(tuple(base))
        for name in names:
            if name != "self":
                out.add((*base, name))
    return out


def parameters(body: str, open_paren: int) -> list[str]:
    """The top-level comma-separated parameters of the list opening at `open_paren`."""
    depth, part, out = 0, "", []
    for ch in body[open_paren + 1 :]:
        if ch in "([<":
            depth += 1
        elif ch in ")]>" and not (ch == ">" and part.endswith("-")):
            if depth == 0:
                break
            depth -= 1
        if ch == "," and depth == 0:
            out.append(part.strip())
            part = ""
        else:
            part += ch
    out.append(part.strip())
    return [p for p in out if p]


def tuple_parameters(body: str) -> list[str]:
    """`name: param` of every function parameter that is a tuple (a pattern or a type)."""
    out = []
    for m in FN_PARAMS.finditer(body):
        for param in parameters(body, m.end() - 1):
            pattern, _, ty = param.partition(":")
            ty = ty.strip().removeprefix("&").removeprefix("mut ").strip()
            if pattern.strip().startswith("(") or ty.startswith("("):
                out.append(f"{m.group(1)}: {' '.join(param.split())}")
    return out


def frame_problems(rel: str, body: str) -> list[str]:
    """A method module importing a sibling method; a `too_many_arguments` allowance or a
    tuple parameter."""
    problems = []
    here = module_path(rel)
    if here[0] != "frame":
        return problems
    own = here[1] if len(here) > 1 and here[1] in METHODS else None
    if own is not None:
        for path in sorted(resolved_paths(rel, body)):
            if len(path) >= 2 and path[0] == "frame" and path[1] in METHODS - {own}:
                problems.append(
                    f"{rel}: method `{own}` imports method `{path[1]}` ({'::'.join(path)});"
                    " what methods share belongs in frame/gpu/, frame/options/ or below"
                )
    found = body.count("too_many_arguments")
    if found:
        problems.append(
            f"{rel}: {found} `too_many_arguments` allowance(s): pass a struct of what"
            " belongs together"
        )
    for param in tuple_parameters(body):
        problems.append(
            f"{rel}: tuple parameter ({param}): pass a struct of what belongs together,"
            " or the values apart"
        )
    return problems


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
        problems += frame_problems(rel, body)
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
