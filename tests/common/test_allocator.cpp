#include <gtest/gtest.h>

#include <cstring>
#include <memory>

#include "coarsegrain/common/allocator.hpp"

#if defined(__GLIBC__)
#include <malloc.h>
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

}  // namespace
}  // namespace coarsegrain
