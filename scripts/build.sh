#!/usr/bin/env bash
# Configures and builds one flavour of coarsegrain: release (default) or asan.
#   scripts/build.sh [release|asan] [targets...]
set -euo pipefail
cd "$(dirname "$0")/.."
flavour=${1:-release}
shift || true
case "$flavour" in
  release) dir=build/release; flags=(-DCMAKE_BUILD_TYPE=Release) ;;
  # clang: the instrumented build took 11.2 min (1239 s user) against g++'s 15.7 min (1677 s).
  asan)    dir=build/asan; flags=(-DCMAKE_BUILD_TYPE=RelWithDebInfo -DCOARSEGRAIN_SANITIZE=ON
                                  -DCOARSEGRAIN_BUILD_BENCH=OFF -DCMAKE_CXX_COMPILER=clang++
                                  -DCMAKE_C_COMPILER=clang) ;;
  *) echo "usage: scripts/build.sh [release|asan] [targets...]" >&2; exit 2 ;;
esac
# ccache (installed by setup.sh) makes rebuilds in fresh clones and git worktrees cheap;
# CCACHE_BASEDIR lets checkouts in different folders share hits. The asan flavour compiles
# with -g1, for which ccache also hashes the build folder (so that the debug info names it):
# CCACHE_NOHASHDIR drops that, or every fresh clone recompiled the whole instrumented build
# (10 of the test command's 17 minutes); a hit then names another checkout's build folder in
# its debug info, which ASan's reports do not need.
if command -v ccache >/dev/null; then
  flags+=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
  export CCACHE_BASEDIR=${CCACHE_BASEDIR:-$PWD}
  if [ "$flavour" = asan ]; then export CCACHE_NOHASHDIR=true; fi
fi
if [ ! -f "$dir/build.ninja" ]; then
  cmake -S . -B "$dir" -G Ninja "${flags[@]}" >/dev/null
fi
ninja -C "$dir" "$@"
