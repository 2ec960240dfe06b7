#!/usr/bin/env bash
# Installs every Debian package coarsegrain needs. Idempotent: when everything is present it
# only runs dpkg-query and exits in well under a second.
set -euo pipefail
packages=(
  build-essential cmake ninja-build pkg-config git ccache
  libeigen3-dev libsuitesparse-dev liblapack-dev libopenblas0-pthread nlohmann-json3-dev libcli11-dev libfmt-dev
  libstb-dev libspectra-dev libgtest-dev libgmock-dev libbenchmark-dev libhypre-dev
  clang libclang-rt-14-dev libomp-dev
  python3 python3-numpy python3-matplotlib calculix-ccx gmsh tetgen
  python3-dev python3-scipy pybind11-dev python3-pybind11 python3-pytest
  python3-venv python3-pip python3-setuptools python3-wheel
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}" >&2
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
# The Python module: a .pth file in Debian's /usr/bin/python3 site directory for local packages
# (/usr/local/lib/python3.X/dist-packages, or the user's site directory when not root) puts this
# checkout's build/release/python on its path, so that `python3 -c "import coarsegrain"` works
# once scripts/build.sh release has built the module (until then the folder does not exist and
# Python skips the line). The last checkout to run setup.sh is the one imported.
python_path="$(cd "$(dirname "$0")/.." && pwd)/build/release/python"
if [ "$(id -u)" -eq 0 ]; then
  site=$(/usr/bin/python3 -c 'import site; print(site.getsitepackages()[0])')
else
  site=$(/usr/bin/python3 -c 'import site; print(site.getusersitepackages())')
fi
if [ "$(cat "$site/coarsegrain.pth" 2>/dev/null)" != "$python_path" ]; then
  mkdir -p "$site"
  echo "$python_path" > "$site/coarsegrain.pth"
  echo "setup: $site/coarsegrain.pth -> $python_path" >&2
fi
