#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include "core/fill_later.h"
#include "core/parallel.h"

namespace tetrefine {

// Where a counting sort put each bucket: bucket b holds entries [start[b], start[b + 1]).
struct BucketLayout {
  FillLater<uint64_t> start;  // num_buckets + 1 offsets into the filled array
  uint64_t size() const { return start.back(); }
};

// Groups the entries that items [0, n) emit into buckets [0, num_buckets), in two passes:
//   count(item, add)   calls add(bucket, k) for the k entries the item puts in `bucket`;
//   allocate(total)    sizes the caller's entry array;
//   fill(item, slot)   makes the same calls as slot(bucket, k), each returning the index of k
//                      consecutive free entries of the caller's array, and writes them.
// The items are cut into contiguous chunks with private counters (ChunkCount), and each chunk's
// entries follow those of the chunks before it, so every bucket lists its entries in item order:
// the same array for any thread count, without atomics. Used by the edge table and the face
// check, where atomic counters cost a locked instruction per entry and bounced cache lines
// between cores.
template <typename Count, typename Allocate, typename Fill>
BucketLayout CountingSort(int64_t n, int64_t num_buckets, Count count, Allocate allocate,
                          Fill fill) {
  const int chunks = ChunkCount(n);
  // Per chunk and bucket: first the chunk's count, then where its next entry goes, relative to
  // the bucket's start (a bucket holds fewer than 2^32 entries: a vertex is in fewer than 2^30
  // tets, since the core accepts at most 5e8).
  FillLater<uint32_t> cursor(static_cast<size_t>(chunks) * num_buckets);
  ForEachChunk(n, chunks, [&](int c, int64_t begin, int64_t end) {
    uint32_t* counts = cursor.data() + static_cast<size_t>(c) * num_buckets;
    std::fill_n(counts, num_buckets, 0u);
    for (int64_t i = begin; i < end; ++i) {
      count(i, [counts](int64_t bucket, uint32_t k) { counts[bucket] += k; });
    }
  });
  BucketLayout layout;
  layout.start.resize(num_buckets + 1);
  FillLater<uint32_t> totals(num_buckets);
  ForEachBlock(num_buckets, [&](int64_t, int64_t begin, int64_t end) {
    for (int64_t b = begin; b < end; ++b) {
      uint32_t running = 0;
      for (int c = 0; c < chunks; ++c) {
        uint32_t& slot = cursor[static_cast<size_t>(c) * num_buckets + b];
        const uint32_t k = slot;
        slot = running;
        running += k;
      }
      totals[b] = running;
    }
  });
  uint64_t total = 0;
  for (int64_t b = 0; b < num_buckets; ++b) {
    layout.start[b] = total;
    total += totals[b];
  }
  layout.start[num_buckets] = total;
  allocate(total);
  const uint64_t* start = layout.start.data();
  ForEachChunk(n, chunks, [&](int c, int64_t begin, int64_t end) {
    uint32_t* next = cursor.data() + static_cast<size_t>(c) * num_buckets;
    for (int64_t i = begin; i < end; ++i) {
      fill(i, [next, start](int64_t bucket, uint32_t k) {
        const uint64_t first = start[bucket] + next[bucket];
        next[bucket] += k;
        return first;
      });
    }
  });
  return layout;
}

}  // namespace tetrefine
