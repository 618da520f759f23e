#include "core/edge_table.h"

#include <algorithm>
#include <atomic>
#include <memory>

#include "core/parallel.h"
#include "core/sorted_tet.h"
#include "core/tet_topology.h"

namespace tetrefine {

uint32_t EdgeTable::FirstOf(uint32_t e) const {
  const auto it = std::upper_bound(first.begin(), first.end(), e);
  return static_cast<uint32_t>(it - first.begin() - 1);
}

EdgeTable BuildEdgeTable(const std::vector<Tet>& tets, int64_t num_points) {
  const int64_t num_tets = static_cast<int64_t>(tets.size());
  // Bucket every tet edge by its smaller endpoint (counting sort), then sort and deduplicate
  // each small bucket. Atomic fills make the order inside a bucket racy; the sort removes that.
  std::unique_ptr<std::atomic<uint32_t>[]> count(new std::atomic<uint32_t>[num_points + 1]);
  for (int64_t v = 0; v <= num_points; ++v) count[v].store(0, std::memory_order_relaxed);
  // With the tet's vertices sorted, its smallest vertex starts 3 edges, the next 2, the next 1.
  ForEachBlock(num_tets, [&](int64_t, int64_t begin, int64_t end) {
    for (int64_t t = begin; t < end; ++t) {
      const SortedTet s = SortTet(tets[t]);
      count[s.v[0]].fetch_add(3, std::memory_order_relaxed);
      count[s.v[1]].fetch_add(2, std::memory_order_relaxed);
      count[s.v[2]].fetch_add(1, std::memory_order_relaxed);
    }
  });
  std::vector<uint64_t> start(num_points + 1);
  uint64_t total = 0;
  for (int64_t v = 0; v < num_points; ++v) {
    start[v] = total;
    total += count[v].load(std::memory_order_relaxed);
    count[v].store(0, std::memory_order_relaxed);
  }
  start[num_points] = total;
  std::vector<uint32_t> raw(total);
  ForEachBlock(num_tets, [&](int64_t, int64_t begin, int64_t end) {
    for (int64_t t = begin; t < end; ++t) {
      const SortedTet s = SortTet(tets[t]);
      for (int i = 0; i < 3; ++i) {
        const uint32_t lo = s.v[i];
        const uint32_t n = static_cast<uint32_t>(3 - i);
        uint32_t* out = raw.data() + start[lo] + count[lo].fetch_add(n, std::memory_order_relaxed);
        for (int j = i + 1; j < 4; ++j) *out++ = s.v[j];
      }
    }
  });
  std::vector<uint32_t> unique_count(num_points, 0);
  ForEachBlock(num_points, [&](int64_t, int64_t begin, int64_t end) {
    for (int64_t v = begin; v < end; ++v) {
      auto* b = raw.data() + start[v];
      auto* e = raw.data() + start[v + 1];
      SortSmall(b, e);
      unique_count[v] = static_cast<uint32_t>(std::unique(b, e) - b);
    }
  });
  EdgeTable table;
  table.first.resize(num_points + 1);
  uint32_t edges = 0;
  for (int64_t v = 0; v < num_points; ++v) {
    table.first[v] = edges;
    edges += unique_count[v];
  }
  table.first[num_points] = edges;
  table.second.resize(edges);
  ForEachBlock(num_points, [&](int64_t, int64_t begin, int64_t end) {
    for (int64_t v = begin; v < end; ++v) {
      std::copy_n(raw.data() + start[v], unique_count[v], table.second.data() + table.first[v]);
    }
  });
  raw = {};
  return table;
}

void AddTetEdges(const std::vector<Tet>& tets, EdgeTable* table) {
  const int64_t num_tets = static_cast<int64_t>(tets.size());
  table->tet_edges.resize(num_tets);
  ForEachBlock(num_tets, [&](int64_t, int64_t begin, int64_t end) {
    for (int64_t t = begin; t < end; ++t) {
      // One pass over each of the three buckets the tet's edges start in: the bucket of v[i]
      // is sorted and holds v[i+1..3] in increasing order.
      const SortedTet s = SortTet(tets[t]);
      for (int i = 0; i < 3; ++i) {
        const uint32_t* p = table->second.data() + table->first[s.v[i]];
        for (int j = i + 1; j < 4; ++j) {
          while (*p < s.v[j]) ++p;
          table->tet_edges[t][EdgeIndex(s.local[i], s.local[j])] =
              static_cast<uint32_t>(p - table->second.data());
        }
      }
    }
  });
}

}  // namespace tetrefine
