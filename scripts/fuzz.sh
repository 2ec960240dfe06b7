#!/usr/bin/env bash
# Fuzzes the mesh readers and the scene loader with libFuzzer, SECONDS each.
#   scripts/fuzz.sh [SECONDS]     (default 60)
# Builds a separate clang build (build-fuzz/, ASan + UBSan + libFuzzer), starts each target from
# its seed corpus (fuzz/corpus/ for the mesh readers, fuzz/corpus_scene/ for the scene loader,
# plus what earlier runs found, kept in build-fuzz/corpus*/), and exits non-zero on a crash,
# leaving the input in build-fuzz/artifacts/. Save such an input under
# tests/data/fuzz_regressions/ (mesh) or tests/data/fuzz_regressions_scene/ (scene) once it is
# fixed: the test suite replays those folders.
set -euo pipefail
seconds="${1:-60}"
root="$(cd "$(dirname "$0")/.." && pwd)"
build="$root/build-fuzz"

CC=clang CXX=clang++ cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCOARSEGRAIN_BUILD_FUZZ=ON -DCOARSEGRAIN_BUILD_TESTS=OFF -DCOARSEGRAIN_BUILD_BENCH=OFF >/dev/null
ninja -C "$build" -j2 fuzz_mesh_readers fuzz_scene

mkdir -p "$build/corpus" "$build/corpus_scene" "$build/artifacts"
export OMP_NUM_THREADS=1
# The target writes each input to a file: in memory (/dev/shm) that runs ~15x faster than on disk.
if [ -z "${TMPDIR:-}" ] && [ -d /dev/shm ] && [ -w /dev/shm ]; then export TMPDIR=/dev/shm; fi
"$build/fuzz/fuzz_mesh_readers" -max_total_time="$seconds" -rss_limit_mb=2048 -max_len=4096 \
  -timeout=10 -print_final_stats=1 -artifact_prefix="$build/artifacts/" \
  "$build/corpus" "$root/fuzz/corpus"
"$build/fuzz/fuzz_scene" -max_total_time="$seconds" -rss_limit_mb=2048 -max_len=4096 \
  -timeout=10 -print_final_stats=1 -artifact_prefix="$build/artifacts/" \
  -dict="$root/fuzz/scene.dict" "$build/corpus_scene" "$root/fuzz/corpus_scene"
