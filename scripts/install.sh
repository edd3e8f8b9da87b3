#!/usr/bin/env bash
# Install everything splatedit needs on Debian 12 (run as root), into ./.venv.
#   System: Python 3 + venv, Mesa lavapipe (CPU Vulkan), the Vulkan loader,
#   glslang (shader compiler, for the SPIR-V staleness test), the Khronos
#   validation layer (the test suite runs with it on), Xvfb + xdotool (window
#   tests) and the DejaVu fonts (editor overlay).
#   Python: this package and its test and docs extras from PyPI, at the exact versions
#   of constraints.txt.
#   Node.js (Debian's nodejs + npm when no node is on PATH) and PlayCanvas's
#   splat-transform into ./.node: the independent reader of our Gaussian PLYs
#   in tests/io/test_splat_transform.py (2.7.1 is the newest release that runs
#   on Debian 12's Node 18; 3.x needs Node >= 22).
set -euo pipefail
cd "$(dirname "$0")/.."

apt_packages=(python3 python3-venv python3-pip mesa-vulkan-drivers libvulkan1 glslang-tools
              vulkan-validationlayers xvfb xauth x11-utils xdotool fonts-dejavu-core)
if command -v apt-get >/dev/null 2>&1; then
    missing=()
    for p in "${apt_packages[@]}"; do
        dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
    done
    if [ ${#missing[@]} -gt 0 ]; then
        echo "install.sh: installing Debian packages: ${missing[*]}"
        export DEBIAN_FRONTEND=noninteractive
        apt-get update -q
        apt-get install -y -q --no-install-recommends "${missing[@]}"
    fi
else
    echo "install.sh: no apt-get here; install these yourself: ${apt_packages[*]}" >&2
fi

if [ ! -x .venv/bin/python ]; then
    python3 -m venv .venv
fi
# Exact versions from constraints.txt (PIP_CONSTRAINT also pins the build
# backend in pip's isolated build environment); see constraints.txt for how to
# update them on purpose.
export PIP_CONSTRAINT="$PWD/constraints.txt"
.venv/bin/python -m pip install -q --upgrade pip
.venv/bin/python -m pip install -q -e '.[test,docs]'
unset PIP_CONSTRAINT

splat_transform_version=2.7.1
if ! command -v node >/dev/null 2>&1 || ! command -v npm >/dev/null 2>&1; then
    if command -v apt-get >/dev/null 2>&1; then
        echo "install.sh: installing Debian packages: nodejs npm"
        export DEBIAN_FRONTEND=noninteractive
        apt-get update -q
        apt-get install -y -q --no-install-recommends nodejs npm
    else
        echo "install.sh: no node/npm; the splat-transform reader test will be skipped" >&2
    fi
fi
if command -v npm >/dev/null 2>&1; then
    installed=$(node -p "require('./.node/node_modules/@playcanvas/splat-transform/package.json').version" \
                2>/dev/null || true)
    if [ "$installed" != "$splat_transform_version" ]; then
        npm install --prefix .node --no-audit --no-fund --loglevel=error \
            "@playcanvas/splat-transform@$splat_transform_version" >/dev/null
    fi
fi
echo "install.sh: ready (.venv)"
