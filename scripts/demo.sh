#!/usr/bin/env bash
# The main job: set up, build, and run `coarsegrain demo` (writes out/demo/).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
scripts/build.sh release coarsegrain_cli >&2
build/release/coarsegrain demo "$@"
