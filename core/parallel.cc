#include "core/parallel.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

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
