#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <memory>

#include "coarsegrain/common/allocator.hpp"

#if defined(__GLIBC__)
#include <malloc.h>
#endif
#if defined(__linux__)
#include <unistd.h>
#endif

#if defined(__has_feature)
#if __has_feature(address_sanitizer)
#define COARSEGRAIN_TEST_ASAN 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__)
#define COARSEGRAIN_TEST_ASAN 1
#endif

namespace coarsegrain {
namespace {

#if defined(COARSEGRAIN_TEST_ASAN) || !defined(__GLIBC__)
TEST(Allocator, RetainFreedMemoryReportsAnAllocatorItCannotTune) {
    // ASan's allocator intercepts mallopt; other C libraries have none.
    EXPECT_FALSE(retain_freed_memory());
}
#else
TEST(Allocator, LargeBlocksComeFromTheHeapAfterRetainFreedMemory) {
    ASSERT_TRUE(retain_freed_memory());
    // A 256 MiB block, far above glibc's default mapping threshold (at most 32 MiB): mapped
    // blocks are counted by mallinfo2's hblks, heap blocks are not.
    const std::size_t before = mallinfo2().hblks;
    const std::size_t bytes = std::size_t{256} << 20;
    std::unique_ptr<char[]> block(new char[bytes]);
    std::memset(block.get(), 1, bytes);
    EXPECT_EQ(mallinfo2().hblks, before);
    EXPECT_GE(mallinfo2().arena, bytes);
}
#endif

#if defined(__linux__)
// The whole pages inside the range read as zeros afterwards (MADV_DONTNEED on private memory);
// the bytes of partial pages at either end keep their values.
TEST(Allocator, ReleasePagesZeroesTheWholePagesInsideTheRange) {
    const std::size_t page = static_cast<std::size_t>(sysconf(_SC_PAGESIZE));
    const std::size_t bytes = 8 * page;
    std::unique_ptr<char[]> block(new char[bytes + page]);
    // From the middle of a page to the middle of another: pages 1..5 of the aligned span whole.
    char* aligned = block.get() + (page - reinterpret_cast<std::uintptr_t>(block.get()) % page);
    std::memset(aligned, 7, bytes);
    release_pages(aligned + page / 2, aligned + 6 * page + page / 2);
    for (std::size_t i = 0; i < bytes; ++i) {
        const bool inside = i >= page && i < 6 * page;
        ASSERT_EQ(aligned[i], inside ? 0 : 7) << "byte " << i;
    }
    release_pages(aligned + page, aligned + page);  // an empty range
    release_pages(aligned + 7 * page + 1, aligned + 7 * page + 2);  // no whole page
    EXPECT_EQ(aligned[7 * page], 7);
}
#endif

}  // namespace
}  // namespace coarsegrain
