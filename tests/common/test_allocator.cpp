#include <gtest/gtest.h>

#include <cstring>
#include <memory>

#include "coarsegrain/common/allocator.hpp"

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace coarsegrain {
namespace {

TEST(Allocator, LargeBlocksComeFromTheHeapAfterRetainFreedMemory) {
#if defined(__GLIBC__)
    if (!retain_freed_memory()) GTEST_SKIP() << "the allocator is not glibc's (a sanitizer?)";
    // A 256 MiB block, far above glibc's default mapping threshold (at most 32 MiB): mapped
    // blocks are counted by mallinfo2's hblks, heap blocks are not.
    const std::size_t before = mallinfo2().hblks;
    const std::size_t bytes = std::size_t{256} << 20;
    std::unique_ptr<char[]> block(new char[bytes]);
    std::memset(block.get(), 1, bytes);
    EXPECT_EQ(mallinfo2().hblks, before);
    EXPECT_GE(mallinfo2().arena, bytes);
#else
    GTEST_SKIP() << "not glibc";
#endif
}

}  // namespace
}  // namespace coarsegrain
