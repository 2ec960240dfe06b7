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
/// its resident set for reuse. The hierarchy's build on 64^3 hexes runs 4-7% faster with less
/// than half the minor page faults (docs/performance.md). Returns whether the allocator took
/// both settings (false under a sanitizer's or another allocator).
bool retain_freed_memory();

/// Returns the free memory the allocator keeps (retain_freed_memory) to the system (glibc's
/// malloc_trim: the free heap's whole pages; a no-op elsewhere). After a phase that freed
/// gigabytes in blocks of many sizes, the next allocations need not fit the holes it left, so
/// they would grow the resident set beside them (the CLI on the touching cubes at 56^3 was
/// killed for memory after the hierarchy's build, at 24.4 GB).
void return_free_memory();

/// Returns the whole pages within [begin, end) to the system, whatever the allocator keeps:
/// memory the program reads no more but cannot free yet, as part of a larger allocation (its
/// contents are lost; the pages read as zeros if touched again). A no-op off Linux.
void release_pages(const void* begin, const void* end);

}  // namespace coarsegrain
