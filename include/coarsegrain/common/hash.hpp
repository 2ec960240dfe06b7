#pragma once
/// @file 64-bit integer mixing for order-independent pattern hashes.
#include <cstdint>

namespace coarsegrain {

/// MurmurHash3's 64-bit finalizer: a bijection of 64-bit words whose output bits each depend on
/// every input bit. Sums of mix64 over a sparse pattern's (column << 32 | row) words hash the
/// pattern independently of the order of its entries.
inline std::uint64_t mix64(std::uint64_t h) {
    h ^= h >> 33;
    h *= 0xff51afd7ed558ccdULL;
    h ^= h >> 33;
    h *= 0xc4ceb9fe1a85ec53ULL;
    return h ^ (h >> 33);
}

}  // namespace coarsegrain
