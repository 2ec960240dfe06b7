#include "coarsegrain/common/allocator.hpp"

#include <climits>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace coarsegrain {

bool retain_freed_memory() {
#if defined(__GLIBC__)
    // mallopt returns 1 on success; sanitizers' interceptors return 0.
    return mallopt(M_MMAP_THRESHOLD, INT_MAX) == 1 && mallopt(M_TRIM_THRESHOLD, INT_MAX) == 1;
#else
    return false;
#endif
}

}  // namespace coarsegrain
