#!/usr/bin/env bash
# Prepares everything the GPU check (scripts/ci/gpu_check.sh, issue 31) needs on a GPU machine
# that has no Rust toolchain, no network and perhaps no Vulkan loader, into git-ignored
# folders of a checkout's root:
#   .gpu/   frame_bench and the gi-core test binaries (release, stripped, in tests.tar.xz), the check's
#           scripts, a copy of tests/ for pytest, lavapipe references for the image
#           comparison (rendered here, two seeds), BUNDLE (what was bundled, from which commit)
#   .whl/   the gi wheel and the Python packages the machine lacks (CPython 3.12)
#   .gl/    the Vulkan loader packages (../shared/tools/gpu-bundle.sh)
# and, for the smoke run here, target/gpu-smoke/ (a virtual environment with only what the
# GPU machine has, and the same wheels for this machine's Python).
#
#   scripts/ci/gpu_bundle.sh                 # then: bash .gpu/gpu_check.sh --smoke
#   scripts/ci/gpu_bundle.sh --dest DIR      # put .gpu/ .whl/ .gl/ into another checkout's root
#
# A device call sends the checkout its session started in: when that is not this one (a
# helper's worktree), bundle with --dest pointing at that checkout. docs/gpu-check.md.
set -euo pipefail
root=$(git rev-parse --show-toplevel)
cd "$root"
dest=$root
while [ $# -gt 0 ]; do
  case $1 in
    --dest) dest=$(cd "$2" && pwd); shift ;;
    -h | --help) sed -n '2,17p' "$0"; exit 0 ;;
    *) echo "gpu_bundle: unknown option $1" >&2; exit 2 ;;
  esac
  shift
done
say() { echo "[gpu_bundle] $*" >&2; }
PY=$root/.venv/bin/python
[ -x "$PY" ] || { say "run make setup first (.venv)"; exit 2; }
# The packages gi and its tests import that the GPU machine's image lacks (it has numpy,
# pytest, hypothesis, pytest-timeout, pytest-xdist: docs/gpu-check.md), at this .venv's
# versions. imageio-ffmpeg (68 MB), pyoidn, ray, nbclient and mypy do not fit or are not
# needed: their test files are left out of the GPU run.
WHEELS=(trimesh OpenImageIO charset-normalizer tqdm flip-evaluator)
# What --smoke runs of part (a): per test binary, its test filters ("*": all); the other
# binaries only list their tests.
SMOKE_TESTS="gpu_direct *
gpu_bsdf_parity *
gpu_texture_parity *
gpu_photon_scatter *
gpu_photon_lazy *
estimators estimator_setting_parses_and_auto_reports_its_choice
frame steady_state_creates_nothing_and_uploads_what_changed serial_frames_equal_overlapped_frames
bidir furnace_matches_analytic"
SMOKE_PYTEST="test_ispm_method_end_to_end or test_ispm_estimators_agree or test_adapter_report \
or test_frame_equals_one_shot or test_steady_state_creates_no_gpu_objects or test_resize \
or test_bidir_renders_with_its_settings or test_hdr_sky_scene or test_save_exr_round_trips \
or test_meshes"
SMOKE_IMAGES="cornell.* cornell-glass.ispm.auto furnace.bidir"

# --- frame_bench and the Vulkan loader: the shared tool, where it can run (it writes
# .git/info/exclude, which a worktree lacks: there the same steps here).
if [ -d .git ]; then
  ../shared/tools/gpu-bundle.sh frame_bench
else
  say "worktree: building frame_bench and fetching the loader as ../shared/tools/gpu-bundle.sh does"
  mkdir -p .gpu
  cargo build -q --release -p gi-core --example frame_bench
  cp target/release/examples/frame_bench .gpu/ && strip .gpu/frame_bench
  if [ ! -d .gl ]; then
    lists=$(mktemp -d); mkdir -p .gl "$lists/partial"
    o="-oAPT::Architecture=amd64 -oAPT::Architectures=amd64 -oDir::State::Lists=$lists"
    # shellcheck disable=SC2086
    apt-get $o update -qq
    # shellcheck disable=SC2086
    (cd .gl && apt-get $o download libvulkan1 libegl1 libglvnd0 libopengl0 libgl1 libglx0 libgles2 >/dev/null)
  fi
fi

# --- The gi-core test binaries (release, as frame_bench: the test profile would rebuild
# every dependency), one file per test target, in one xz archive: stripped they are ~150 MB,
# mostly the same code, which a 256 MiB dictionary finds across files (~11 MB).
say "building the test binaries"
rm -rf target/gpu-tests .gpu/tests.tar.xz .gpu/tests && mkdir -p target/gpu-tests/tests
cargo test -q --release -p gi-core --no-run # its errors readable; then their paths
cargo test -q --release -p gi-core --no-run --message-format=json 2>/dev/null |
  "$PY" -c '
import json, sys
for line in sys.stdin:
    m = json.loads(line)
    if m.get("reason") == "compiler-artifact" and m.get("executable") and m["profile"]["test"]:
        t = m["target"]
        print(("lib" if "lib" in t["kind"] else t["name"]), m["executable"])
' | while read -r name exe; do
  cp "$exe" "target/gpu-tests/tests/$name" && strip "target/gpu-tests/tests/$name"
done
n=$(ls target/gpu-tests/tests | wc -l)
[ "$n" -gt 10 ] || { say "only $n test binaries"; exit 1; }
sum=$(cd target/gpu-tests && sha256sum tests/* | sha256sum | cut -c1-16)
if [ "$(cat target/gpu-tests-archive/sum 2>/dev/null)" != "$sum" ]; then
  say "compressing $n test binaries (a few minutes)"
  rm -rf target/gpu-tests-archive && mkdir -p target/gpu-tests-archive
  tar -cf - -C target/gpu-tests tests | xz -T1 --lzma2=preset=6,dict=256MiB >target/gpu-tests-archive/tests.tar.xz
  echo "$sum" >target/gpu-tests-archive/sum
fi
cp target/gpu-tests-archive/tests.tar.xz .gpu/

# --- The gi wheel, and the packages above for CPython 3.12 (the GPU machine's) into .whl/,
# for this Python into target/gpu-smoke/whl/.
say "building the wheel"
rm -rf target/gpu-wheel .whl target/gpu-smoke/whl
mkdir -p .whl target/gpu-smoke/whl
"$root/.venv/bin/maturin" build -q --release --out target/gpu-wheel >/dev/null
cp target/gpu-wheel/gi-*.whl .whl/
cp target/gpu-wheel/gi-*.whl target/gpu-smoke/whl/
pins=()
for w in "${WHEELS[@]}"; do
  v=$("$PY" -m pip show "$w" 2>/dev/null | sed -n 's/^Version: //p')
  [ -n "$v" ] || { say "$w is not in .venv"; exit 1; }
  pins+=("$w==$v")
done
plat=()
for p in manylinux_2_28 manylinux_2_27 manylinux_2_17 manylinux2014 manylinux1 manylinux_2_5; do
  plat+=(--platform "${p}_x86_64")
done
"$PY" -m pip download -q --no-deps --only-binary=:all: --python-version 3.12 --implementation cp \
  "${plat[@]}" -d .whl "${pins[@]}"
"$PY" -m pip download -q --no-deps --only-binary=:all: -d target/gpu-smoke/whl "${pins[@]}"
# The GPU photon trace's table (docs/bench/gpu-photon.md), part (c) of the check.
cargo build -q --release -p gi-core --example gpu_photon_bench
cp target/release/examples/gpu_photon_bench .gpu/ && strip .gpu/gpu_photon_bench

# Every wheel installs on CPython 3.12 / x86-64 with glibc 2.39 (the GPU machine's; pip
# matches each manylinux_2_N tag exactly, so all N up to 39): a dry run.
tags=(--platform linux_x86_64 --platform manylinux2014_x86_64 --platform manylinux1_x86_64)
for n in $(seq 5 39); do tags+=(--platform "manylinux_2_${n}_x86_64"); done
"$PY" -m pip install -q --dry-run --no-index --no-deps --only-binary=:all: --python-version 3.12 \
  --implementation cp "${tags[@]}" --target /tmp/gpu-bundle-dry .whl/*.whl

# --- The smoke run's Python: only what the GPU machine's image has of what the check uses.
if [ ! -x target/gpu-smoke/venv/bin/python ]; then
  say "creating target/gpu-smoke/venv"
  python3 -m venv target/gpu-smoke/venv
  target/gpu-smoke/venv/bin/python -m pip install -q numpy pytest hypothesis pytest-timeout pytest-xdist
fi

# --- The check's scripts, tests/ for pytest (with the files it reads), the smoke lists.
cp scripts/ci/gpu_check.sh scripts/ci/gpu_images.py scripts/ci/gpu_summary.py scripts/ci/gpu_pytest_plugin.py .gpu/
rm -rf .gpu/pytests && mkdir -p .gpu/pytests/docs .gpu/pytests/scripts
# What the tests read beside tests/: the README (its examples run), docs/examples and
# docs/scenes (Mitsuba scenes and references), the scripts some tests run (0.8 MB in all).
cp -r tests pyproject.toml README.md .gpu/pytests/
cp -r docs/examples docs/scenes .gpu/pytests/docs/
cp -r scripts/. .gpu/pytests/scripts/
find .gpu/pytests -name __pycache__ -prune -exec rm -rf {} +
rm -rf .gpu/probes && cp -r scripts/probe/gpu_probes .gpu/probes
echo "$SMOKE_TESTS" >.gpu/smoke_tests.txt
echo "$SMOKE_PYTEST" >.gpu/smoke_pytest.txt
echo "$SMOKE_IMAGES" >.gpu/smoke_images.txt

# --- The lavapipe references, rendered with the bundled wheel (cached per source state).
key=$(git ls-files -z -co --exclude-standard crates python scripts/ci/gpu_images.py |
  xargs -0 sha256sum | sha256sum | cut -c1-16)
cache=target/gpu-refs/$key
if [ ! -f "$cache/meta.json" ]; then
  say "rendering the lavapipe references into $cache (a few minutes)"
  site=$(mktemp -d)
  "$PY" -m pip install -q --no-index --no-deps --target "$site" target/gpu-wheel/gi-*.whl
  rm -rf "$cache.tmp"
  GI_ADAPTER=cpu PYTHONPATH=$site "$PY" scripts/ci/gpu_images.py render --out "$cache.tmp" >&2
  mv "$cache.tmp" "$cache"
  rm -rf "$site"
fi
rm -rf .gpu/refs && cp -r "$cache" .gpu/refs

# --- What was bundled.
dirty=$(git diff --quiet HEAD -- . && echo "" || echo "+uncommitted changes")
{
  echo "gi $("$PY" -c 'import gi; print(gi.__version__)') at $(git rev-parse --short HEAD)$dirty, bundled $(date -u +%FT%TZ)"
  echo "references: $(head -c 300 .gpu/refs/meta.json | tr -d '\n' | sed 's/.*"adapter": "\([^"]*\)".*/\1/')"
  echo "test binaries: $(ls target/gpu-tests/tests | tr '\n' ' ')"
  echo "wheels: $(ls .whl | tr '\n' ' ')"
} >.gpu/BUNDLE

# --- Into the destination checkout, and the size of what a device call carries.
if [ "$dest" != "$root" ]; then
  say "copying .gpu .whl .gl to $dest"
  rm -rf "$dest/.gpu" "$dest/.whl" "$dest/.gl"
  cp -r .gpu .whl .gl "$dest/"
fi
cd "$dest"
exclude=$(git rev-parse --git-path info/exclude)
mkdir -p "$(dirname "$exclude")"
for d in .gpu .gl .whl; do # as the shared tool does: ignored where .gitignore does not
  git check-ignore -q "$d" || echo "/$d/" >>"$exclude"
done
tree=$(git ls-files -co --exclude-standard -z | du -cb --files0-from=- 2>/dev/null | tail -1 | cut -f1)
carried=$(du -sb .gpu .whl .gl | awk '{s += $1} END {print s}')
total=$((tree + carried))
du -sh .gpu .gpu/tests.tar.xz .gpu/frame_bench .gpu/refs .whl .gl >&2
say "working tree $((tree / 1024)) KiB + carried $((carried / 1024)) KiB = $((total / 1048576)) MiB of 64"
[ "$total" -lt $((60 * 1048576)) ] || { say "over 60 MiB: the device call would refuse it"; exit 1; }
