#!/usr/bin/env bash
# Tests the installed package: installs a build (default build/release) into a temporary prefix,
# moves the prefix (an install must not depend on where it was made), imports the Python package
# it installed (COARSEGRAIN_INSTALL_PYTHONDIR), builds and runs
# tests/install/consumer against it with find_package(coarsegrain), and runs the installed
# `coarsegrain demo --scale 0.25`, whose pictures must come from the installed plotting scripts;
# then installs the Python module with `pip install --no-build-isolation .` into a virtual
# environment (Debian's /usr/bin/python3, --system-site-packages; setup.py builds into build/pip,
# from ccache when build/release was built) and coarsens the demo beam with it.
#   scripts/test_install.sh [BUILD_DIR]
# Leaves nothing behind (the temporary folder is removed on exit, also on failure).
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
build=${1:-build/release}

fail() {
  echo "test_install: FAILED: $*" >&2
  exit 1
}
# Runs a step quietly; on failure shows its output and names the step.
step() {
  local what=$1
  shift
  if ! "$@" >"$tmp/step.log" 2>&1; then
    tail -n 40 "$tmp/step.log" >&2
    fail "$what (command: $*)"
  fi
}

[ -f "$build/build.ninja" ] || fail "$build is not a configured build (run scripts/build.sh release)"
[ -x "$build/coarsegrain" ] || fail "$build/coarsegrain not built (run scripts/build.sh release)"
tmp=$(mktemp -d "${TMPDIR:-/tmp}/coarsegrain-install.XXXXXX")
trap 'rm -rf "$tmp"' EXIT

step "cmake --install $build" cmake --install "$build" --prefix "$tmp/stage"
mv "$tmp/stage" "$tmp/prefix"
prefix=$tmp/prefix
for f in bin/coarsegrain lib/libcoarsegrain.a include/coarsegrain/scene/scene.hpp \
         share/coarsegrain/scripts/plot_report.py share/coarsegrain/scripts/plot_mra.py \
         share/coarsegrain/scripts/plot_animation.py \
         lib/cmake/coarsegrain/coarsegrainConfig.cmake \
         lib/cmake/coarsegrain/coarsegrainConfigVersion.cmake \
         lib/cmake/coarsegrain/coarsegrainTargets.cmake lib/cmake/coarsegrain/FindCHOLMOD.cmake; do
  [ -e "$prefix/$f" ] || fail "the install has no $f"
done
# The Python package, where COARSEGRAIN_INSTALL_PYTHONDIR says (relative: under the prefix).
pydir=$(sed -n 's/^COARSEGRAIN_INSTALL_PYTHONDIR:PATH=//p' "$build/CMakeCache.txt")
case "$pydir" in
  "") fail "$build has no COARSEGRAIN_INSTALL_PYTHONDIR (configured without the Python module?)" ;;
  /*) pyroot=$pydir ;;
  *) pyroot=$prefix/$pydir ;;
esac
[ -f "$pyroot/coarsegrain/__init__.py" ] || fail "the install has no $pyroot/coarsegrain/__init__.py"
compgen -G "$pyroot/coarsegrain/_core*.so" >/dev/null ||
  fail "the install has no extension $pyroot/coarsegrain/_core*.so"
(cd "$tmp" && env -u PYTHONPATH PYTHONPATH="$pyroot" /usr/bin/python3 -c '
import os, numpy, coarsegrain as cg
assert cg.__file__.startswith(os.environ["PYTHONPATH"]), cg.__file__
m = cg.coarsen(cg.scene_from_dict(cg.demo_scene(0.25)), "mra").coarse_model
U = m.to_fine @ numpy.ones((m.num_dofs, 2))
assert U.shape == (m.to_fine.shape[0], 2), U.shape
') || fail "the Python package installed in $pyroot"
if grep -qF "$root/scripts" "$prefix/bin/coarsegrain"; then
  fail "the installed binary names the source tree's scripts folder $root/scripts"
fi

# The consumer: its sources are copied into the temporary folder so that, with CCACHE_BASEDIR
# there, every path ccache sees is relative and a rerun is a cache hit.
cp -r tests/install/consumer "$tmp/consumer"
launcher=()
if command -v ccache >/dev/null; then
  launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
  export CCACHE_BASEDIR=$tmp
fi
step "configuring tests/install/consumer against the install" \
  cmake -S "$tmp/consumer" -B "$tmp/consumer-build" -G Ninja -DCMAKE_BUILD_TYPE=Release \
        -DCMAKE_PREFIX_PATH="$prefix" "${launcher[@]}"
found=$(sed -n 's/^coarsegrain_DIR:PATH=//p' "$tmp/consumer-build/CMakeCache.txt")
[ "$found" = "$prefix/lib/cmake/coarsegrain" ] ||
  fail "the consumer found coarsegrain in '$found', not in the install $prefix/lib/cmake/coarsegrain"
step "building tests/install/consumer" cmake --build "$tmp/consumer-build"
"$tmp/consumer-build/consumer" || fail "the consumer's checks (tests/install/consumer/main.cpp)"

# The installed tool finds its scripts in $prefix/share/coarsegrain/scripts: nothing else holds
# them (the source path is not compiled in, COARSEGRAIN_SCRIPTS is unset).
out=$tmp/demo
if ! env -u COARSEGRAIN_SCRIPTS -u COARSEGRAIN_PYTHON "$prefix/bin/coarsegrain" --quiet demo \
       --scale 0.25 --out "$out" >"$tmp/demo.log" 2>&1; then
  tail -n 40 "$tmp/demo.log" >&2
  fail "the installed coarsegrain demo --scale 0.25"
fi
if grep -q "not made" "$tmp/demo.log"; then
  cat "$tmp/demo.log" >&2
  fail "the installed coarsegrain did not make its plots"
fi
for png in deformed.png methods.png; do
  [ -s "$out/$png" ] || fail "the installed coarsegrain demo made no $png"
done

# The Python module in a virtual environment: imported from there (its site-packages comes before
# the system's, where the .pth of scripts/setup.sh names build/release/python), and it runs.
step "creating a virtual environment" /usr/bin/python3 -m venv --system-site-packages "$tmp/venv"
step "pip install --no-build-isolation ." "$tmp/venv/bin/pip" install --no-build-isolation "$root"
(cd "$tmp" && env -u PYTHONPATH "$tmp/venv/bin/python" -c '
import sys, coarsegrain as cg
assert cg.__file__.startswith(sys.prefix), cg.__file__
r = cg.coarsen(cg.scene_from_dict(cg.demo_scene(0.25)), "effective-tensor")
assert set(r.errors) == {"energy_rel", "energy_over_load", "l2_rel", "max_displacement_rel",
                         "compliance_ratio", "stress_rel"}, r.errors
') || fail "the Python module installed by pip"
echo "test_install: the install, the consumer, the installed tool's plots and pip install pass" >&2
