#pragma once

#include <algorithm>
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

// Contiguous chunks of [0, n) for passes that keep private state per chunk (see CountingSort):
// one per worker of the current arena, two per worker when there are several (for balance), at
// most kMaxChunks, and never smaller than a block.
inline constexpr int kMaxChunks = 16;
int ChunkCount(int64_t n);

// Calls body(chunk, begin, end) for the `chunks` equal contiguous pieces of [0, n), in parallel.
void ForEachChunk(int64_t n, int chunks, const std::function<void(int, int64_t, int64_t)>& body);

// The smallest i in [0, n) for which bad(i) holds, or n. Parallel; the answer does not depend
// on timing.
int64_t FirstIndexWhere(int64_t n, const std::function<bool(int64_t)>& bad);

// Sorts [first, last): insertion sort for the short runs the per-vertex buckets hold (a dozen
// entries), std::sort beyond.
template <typename T, typename Less = std::less<T>>
void SortSmall(T* first, T* last, Less less = Less()) {
  if (last - first > 32) {
    std::sort(first, last, less);
    return;
  }
  for (T* i = first + 1; i < last; ++i) {
    T v = *i;
    T* j = i;
    for (; j > first && less(v, *(j - 1)); --j) *j = *(j - 1);
    *j = v;
  }
}

// Exclusive prefix sum of counts in place; returns the total.
int64_t ExclusivePrefixSum(std::vector<int64_t>& counts);

}  // namespace tetrefine
