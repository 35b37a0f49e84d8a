#!/usr/bin/env bash
# Sets up a fresh Debian/Ubuntu machine with Rust and Python 3 for gi, saying what it does:
#
#   scripts/ci/setup.sh render   what rendering needs: Mesa lavapipe (software Vulkan, for the
#                             GPU passes), a virtual environment in .venv, and gi built by
#                             maturin (cargo's progress shown) and installed into it.
#   scripts/ci/setup.sh test     the same, plus the test tools (the `test` extra: pytest, Ray,
#                             Playwright, ...), Chromium (the viewer's browser test drives
#                             it headless), rustfmt and clippy.
#
# VENV=dir puts the environment elsewhere (default .venv). Running it again rebuilds gi
# incrementally (cargo) and installs only what is missing.
set -euo pipefail
cd "$(dirname "$0")/../.."
mode=${1:-render}
case "$mode" in
  render | test) ;;
  *) echo "usage: scripts/ci/setup.sh [render|test]" >&2; exit 2 ;;
esac
VENV=${VENV:-.venv}
PYTHON=${PYTHON:-python3}
step() { printf '\nsetup (%s): %s\n' "$mode" "$*" >&2; }

packages=(mesa-vulkan-drivers libvulkan1)
[ "$mode" = test ] && packages+=(chromium)
need_apt=()
for pkg in "${packages[@]}"; do
  dpkg -s "$pkg" >/dev/null 2>&1 || need_apt+=("$pkg")
done
if [ ${#need_apt[@]} -gt 0 ]; then
  if [ "$(id -u)" -eq 0 ]; then SUDO=""; elif command -v sudo >/dev/null; then SUDO="sudo"; else
    echo "setup: please install ${need_apt[*]} (apt-get install ${need_apt[*]})" >&2; exit 1
  fi
  step "installing ${need_apt[*]} (apt-get)"
  $SUDO apt-get update
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y "${need_apt[@]}"
else
  step "system packages present: ${packages[*]}"
fi

if [ "$mode" = test ]; then
  for comp in rustfmt clippy; do
    if ! cargo "${comp/rustfmt/fmt}" --version >/dev/null 2>&1; then
      step "adding the Rust component $comp"
      rustup component add "$comp"
    fi
  done
fi

if [ ! -x "$VENV/bin/python" ]; then
  step "making the virtual environment $VENV"
  "$PYTHON" -m venv "$VENV"
fi
step "installing the build tool (maturin) into $VENV"
"$VENV/bin/python" -m pip install --upgrade pip 'maturin>=1.9.4,<2'

# maturin rather than `pip install .`: pip shows nothing of a build backend's output, and
# the release build of the Rust core takes minutes on a small machine the first time.
step "building gi (cargo, release; minutes the first time, seconds after)"
rm -rf target/setup-wheels
"$VENV/bin/maturin" build --release --interpreter "$VENV/bin/python" --out target/setup-wheels
wheel=$(ls target/setup-wheels/gi-*.whl)

extra=""
[ "$mode" = test ] && extra="[test]"
step "installing gi and its dependencies${extra:+ (with the test tools)} into $VENV"
"$VENV/bin/python" -m pip install --force-reinstall --no-deps "$wheel"
"$VENV/bin/python" -m pip install "$wheel$extra"

step "done: $VENV/bin/gi (or: source $VENV/bin/activate, then gi)"
"$VENV/bin/gi" --version
