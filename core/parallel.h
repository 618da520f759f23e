#pragma once

#include <cstdint>
#include <functional>
#include <vector>

namespace tetrefine {

// Work is cut into blocks of a fixed size that does not depend on the thread count, and every
// reduction combines per-block partial results in block order. That keeps floating-point sums,
// and so every output bit, independent of how many threads ran.
inline constexpr int64_t kBlockSize = 4096;

inline int64_t BlockCount(int64_t n) { return (n + kBlockSize - 1) / kBlockSize; }

// Calls body(block, begin, end) for every block of [0, n), in parallel on the current TBB arena.
void ForEachBlock(int64_t n, const std::function<void(int64_t, int64_t, int64_t)>& body);

// Exclusive prefix sum of counts in place; returns the total.
int64_t ExclusivePrefixSum(std::vector<int64_t>& counts);

}  // namespace tetrefine
