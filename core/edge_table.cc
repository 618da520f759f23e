#include "core/edge_table.h"

#include <algorithm>
#include <atomic>
#include <memory>

#include "core/parallel.h"
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
  ForEachBlock(num_tets, [&](int64_t, int64_t begin, int64_t end) {
    for (int64_t t = begin; t < end; ++t) {
      for (const auto& e : kTetEdges) {
        const uint32_t a = tets[t][e[0]], b = tets[t][e[1]];
        count[std::min(a, b)].fetch_add(1, std::memory_order_relaxed);
      }
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
      for (const auto& e : kTetEdges) {
        const uint32_t a = tets[t][e[0]], b = tets[t][e[1]];
        const uint32_t lo = std::min(a, b);
        const uint32_t slot = count[lo].fetch_add(1, std::memory_order_relaxed);
        raw[start[lo] + slot] = std::max(a, b);
      }
    }
  });
  std::vector<uint32_t> unique_count(num_points, 0);
  ForEachBlock(num_points, [&](int64_t, int64_t begin, int64_t end) {
    for (int64_t v = begin; v < end; ++v) {
      auto* b = raw.data() + start[v];
      auto* e = raw.data() + start[v + 1];
      std::sort(b, e);
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
  table.tet_edges.resize(num_tets);
  ForEachBlock(num_tets, [&](int64_t, int64_t begin, int64_t end) {
    for (int64_t t = begin; t < end; ++t) {
      for (int k = 0; k < 6; ++k) {
        const uint32_t a = tets[t][kTetEdges[k][0]], b = tets[t][kTetEdges[k][1]];
        const uint32_t lo = std::min(a, b), hi = std::max(a, b);
        const uint32_t* first = table.second.data() + table.first[lo];
        const uint32_t* last = table.second.data() + table.first[lo + 1];
        table.tet_edges[t][k] =
            static_cast<uint32_t>(std::lower_bound(first, last, hi) - table.second.data());
      }
    }
  });
  return table;
}

}  // namespace tetrefine
