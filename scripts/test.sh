#!/usr/bin/env bash
# The whole test suite: set up, build, run every test (Release), test the installed package
# (scripts/test_install.sh), then a fast subset under AddressSanitizer +
# UndefinedBehaviorSanitizer. With COARSEGRAIN_FUZZ_SECONDS=N it also fuzzes the mesh readers
# and the scene loader for N seconds each (scripts/fuzz.sh; a third, clang, build).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
jobs=$(nproc)
# ctest runs $jobs test programs at once, each with its OpenMP threads; OpenBLAS threads would
# spin on cores the other programs need (docs/guide.md, "The direct solver").
export OPENBLAS_NUM_THREADS=1

echo "== release build and full test suite" >&2
scripts/build.sh release
ctest --test-dir build/release --output-on-failure -j "$jobs"

echo "== the installed package: cmake --install, a find_package consumer, the installed tool" >&2
scripts/test_install.sh build/release

echo "== sanitizer build (ASan + UBSan), fast subset" >&2
scripts/build.sh asan coarsegrain_tests coarsegrain_cli
ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
  ctest --test-dir build/asan --output-on-failure -j "$jobs" -E 'Slow'

if [ -n "${COARSEGRAIN_FUZZ_SECONDS:-}" ]; then
  echo "== fuzzing the mesh readers and the scene loader, ${COARSEGRAIN_FUZZ_SECONDS} s each" >&2
  scripts/fuzz.sh "$COARSEGRAIN_FUZZ_SECONDS"
fi
echo "all tests passed" >&2
