#include "core/parallel.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>

namespace tetrefine {

void ForEachBlock(int64_t n, const std::function<void(int64_t, int64_t, int64_t)>& body) {
  const int64_t blocks = BlockCount(n);
  tbb::parallel_for(tbb::blocked_range<int64_t>(0, blocks), [&](const auto& r) {
    for (int64_t b = r.begin(); b != r.end(); ++b) {
      const int64_t begin = b * kBlockSize;
      const int64_t end = begin + kBlockSize < n ? begin + kBlockSize : n;
      body(b, begin, end);
    }
  });
}

int ChunkCount(int64_t n) {
  const int64_t workers = tbb::this_task_arena::max_concurrency();
  const int64_t wanted = workers > 1 ? std::min<int64_t>(2 * workers, kMaxChunks) : 1;
  return static_cast<int>(std::max<int64_t>(1, std::min(wanted, n / kBlockSize)));
}

void ForEachChunk(int64_t n, int chunks, const std::function<void(int, int64_t, int64_t)>& body) {
  tbb::parallel_for(
      tbb::blocked_range<int>(0, chunks, 1),
      [&](const auto& r) {
        for (int c = r.begin(); c != r.end(); ++c) {
          body(c, n * c / chunks, n * (c + 1) / chunks);
        }
      },
      tbb::simple_partitioner());
}

int64_t FirstIndexWhere(int64_t n, const std::function<bool(int64_t)>& bad) {
  std::atomic<int64_t> first{n};
  ForEachBlock(n, [&](int64_t, int64_t begin, int64_t end) {
    for (int64_t i = begin; i < end && i < first.load(std::memory_order_relaxed); ++i) {
      if (!bad(i)) continue;
      int64_t cur = first.load();
      while (i < cur && !first.compare_exchange_weak(cur, i)) {
      }
      return;
    }
  });
  return first.load();
}

int64_t ExclusivePrefixSum(std::vector<int64_t>& counts) {
  int64_t total = 0;
  for (int64_t& c : counts) {
    const int64_t v = c;
    c = total;
    total += v;
  }
  return total;
}

}  // namespace tetrefine
