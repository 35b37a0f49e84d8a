#!/usr/bin/env bash
# Installs everything gi needs on a fresh Debian/Ubuntu machine with Rust and Python 3:
# Mesa lavapipe (software Vulkan, for the GPU passes), Chromium (the viewer's browser test
# drives it headless), a virtual environment in .venv, and gi itself (built by maturin)
# with its test tools.
set -euo pipefail
cd "$(dirname "$0")/../.."

need_apt=()
for pkg in mesa-vulkan-drivers libvulkan1 chromium; do
  dpkg -s "$pkg" >/dev/null 2>&1 || need_apt+=("$pkg")
done
if [ ${#need_apt[@]} -gt 0 ]; then
  if [ "$(id -u)" -eq 0 ]; then SUDO=""; elif command -v sudo >/dev/null; then SUDO="sudo"; else
    echo "setup: please install ${need_apt[*]} (apt-get install ${need_apt[*]})" >&2; exit 1
  fi
  echo "setup: installing ${need_apt[*]}" >&2
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${need_apt[@]}" >/dev/null
fi

for comp in rustfmt clippy; do
  if ! cargo "${comp/rustfmt/fmt}" --version >/dev/null 2>&1; then rustup component add "$comp"; fi
done

PYTHON=${PYTHON:-python3}
[ -x .venv/bin/python ] || "$PYTHON" -m venv .venv
.venv/bin/python -m pip install -q --upgrade pip
.venv/bin/python -m pip install -q ".[test]"
