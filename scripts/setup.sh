#!/usr/bin/env bash
# Installs every Debian package coarsegrain needs. Idempotent: when everything is present it
# only runs dpkg-query and exits in well under a second.
set -euo pipefail
packages=(
  build-essential cmake ninja-build pkg-config git ccache
  libeigen3-dev libsuitesparse-dev liblapack-dev libopenblas0-pthread nlohmann-json3-dev libcli11-dev libfmt-dev
  libstb-dev libspectra-dev libgtest-dev libgmock-dev libbenchmark-dev
  clang libclang-rt-14-dev libomp-dev
  python3 python3-numpy python3-matplotlib calculix-ccx gmsh tetgen
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
