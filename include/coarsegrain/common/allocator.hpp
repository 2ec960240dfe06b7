#pragma once
/// @file The process's memory allocator, tuned for builds that allocate and free matrices of
/// gigabytes.

namespace coarsegrain {

/// Makes glibc's malloc keep the memory a program frees for its next allocations: blocks of up
/// to 2 GiB come from the heap instead of a mapping of their own (M_MMAP_THRESHOLD), and the
/// heap returns its free top to the kernel only beyond 2 GiB (M_TRIM_THRESHOLD). By default
/// glibc maps every block above its dynamic threshold (at most 32 MiB) afresh and unmaps it when
/// freed, so that the kernel zeroes every page of the next such block again. A call for
/// programs (the CLI and the benchmarks make it first thing); the library never makes it, as it
/// changes the allocator of the whole process. The price: memory freed by the program stays in
/// its resident set for reuse. Measured (bench_mra 64 64 64 2 5 1e-7 fine dirac, the build
/// alone, glibc 2.36, two runs each way in one session; the same settings through
/// GLIBC_TUNABLES): build 315.2 -> 301.8 s and 299.0 -> 277.2 s, minor page faults 9.0M ->
/// 3.9M, system time 57 -> 40-47 s, the Galerkin product A^1 41-62 -> 35-50 s. Returns whether
/// the allocator took both settings (false under a sanitizer's or another allocator).
bool retain_freed_memory();

}  // namespace coarsegrain
