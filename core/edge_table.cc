#include "core/edge_table.h"

#include <algorithm>
#include <bit>

#include "core/counting_sort.h"
#include "core/parallel.h"
#include "core/sorted_tet.h"
#include "core/tet_topology.h"

namespace tetrefine {

uint32_t EdgeTable::FirstOf(uint32_t e) const {
  const auto it = std::upper_bound(first.begin(), first.end(), e);
  return static_cast<uint32_t>(it - first.begin() - 1);
}

namespace {

// Sorts [b, e) and drops repeats; returns the new end. A bucket lists each edge once per tet
// around it (five to six times inside a mesh), and the old vertices of a refined mesh collect
// buckets of a hundred entries and more: there a small hash set drops the repeats first, so the
// sort only sees the dozen or so distinct edges.
uint32_t* SortUnique(uint32_t* b, uint32_t* e, std::vector<uint32_t>& seen) {
  constexpr uint32_t kEmpty = ~uint32_t{0};  // vertex ids are below 2^31
  if (e - b <= 32) {
    SortSmall(b, e);
    return std::unique(b, e);
  }
  const size_t slots = std::bit_ceil(static_cast<size_t>(2 * (e - b)));
  seen.assign(slots, kEmpty);
  const int shift = 32 - std::countr_zero(slots);
  uint32_t* out = b;
  for (const uint32_t* p = b; p < e; ++p) {
    const uint32_t w = *p;
    // Fibonacci hashing; linear probing in a table at most half full.
    size_t h = static_cast<uint32_t>(w * 0x9E3779B1u) >> shift;
    while (seen[h] != kEmpty && seen[h] != w) h = (h + 1) & (slots - 1);
    if (seen[h] == w) continue;
    seen[h] = w;
    *out++ = w;
  }
  SortSmall(b, out);
  return out;
}

// Sorts and deduplicates each of the num_points buckets of `raw` in place; returns how many
// distinct entries each keeps at its start.
FillLater<uint32_t> SortUniqueBuckets(uint32_t* raw, const BucketLayout& layout,
                                      int64_t num_points) {
  const auto& start = layout.start;
  FillLater<uint32_t> unique_count(num_points);
  ForEachBlock(num_points, [&](int64_t, int64_t begin, int64_t end) {
    std::vector<uint32_t> seen;
    for (int64_t v = begin; v < end; ++v) {
      uint32_t* b = raw + start[v];
      uint32_t* e = raw + start[v + 1];
      unique_count[v] = static_cast<uint32_t>(SortUnique(b, e, seen) - b);
    }
  });
  return unique_count;
}

}  // namespace

EdgeTable BuildEdgeTable(const std::vector<Tet>& tets, int64_t num_points) {
  const int64_t num_tets = static_cast<int64_t>(tets.size());
  // Bucket every tet edge by its smaller endpoint (a counting sort), then sort and deduplicate
  // each small bucket. With the tet's vertices sorted, its smallest vertex starts 3 edges, the
  // next 2, the next 1.
  // Not value-initialised: every entry is written by the fill pass.
  // Not kept across a refinement's iterations: alive through the subdivision, its 24 bytes a
  // tet raised the reproduction's peak added memory by 1.21x at the median and 1.51x on its
  // largest runs (docs/results, 2026-11-24), for a kernel-time saving within the VM's noise.
  FillLater<uint32_t> buckets;
  uint32_t* raw = nullptr;
  const BucketLayout layout = CountingSort(
      num_tets, num_points,
      [&](int64_t t, auto add) {
        const SortedTet s = SortTet(tets[t]);
        add(s.v[0], 3);
        add(s.v[1], 2);
        add(s.v[2], 1);
      },
      [&](uint64_t total) {
        // FillLater offers huge pages: in 4 KiB pages this array took 80% of a whole call's
        // page faults (bench/core_bench BM_ToConvergence, 2026-11-24).
        buckets.resize(total);
        raw = buckets.data();
      },
      [&](int64_t t, auto slot) {
        const SortedTet s = SortTet(tets[t]);
        for (int i = 0; i < 3; ++i) {
          uint32_t* out = raw + slot(s.v[i], static_cast<uint32_t>(3 - i));
          for (int j = i + 1; j < 4; ++j) *out++ = s.v[j];
        }
      });
  const auto& start = layout.start;
  const FillLater<uint32_t> unique_count = SortUniqueBuckets(raw, layout, num_points);
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
      std::copy_n(raw + start[v], unique_count[v], table.second.data() + table.first[v]);
    }
  });
  return table;
}

EdgeTable UpdateEdgeTable(const EdgeTable& before, const FillLater<uint8_t>& split,
                          const std::vector<Tet>& tets, const std::vector<int32_t>& tet_iteration,
                          int32_t made_in, int64_t num_points, FillLater<uint32_t>* remap) {
  const int64_t num_tets = static_cast<int64_t>(tets.size());
  const int64_t old_points = static_cast<int64_t>(before.first.size()) - 1;
  const uint32_t first_new = static_cast<uint32_t>(old_points);
  // The children's edges that have a new vertex, bucketed by their smaller endpoint: calls
  // f(v, ends, n) for each vertex v of child tet t that starts such edges, to the n vertices
  // ends[0..n). In a sorted tet the new vertices are a suffix, from index `from`: vertex v[i]
  // starts the edges to v[max(i + 1, from)..3].
  const auto new_edges_of = [&](int64_t t, auto f) {
    if (tet_iteration[t] != made_in) return;
    const SortedTet s = SortTet(tets[t]);
    int from = 4;
    while (from > 0 && s.v[from - 1] >= first_new) --from;
    for (int i = 0; i < 3; ++i) {
      const int j0 = std::max(i + 1, from);
      if (j0 < 4) f(s.v[i], s.v.data() + j0, static_cast<uint32_t>(4 - j0));
    }
  };
  FillLater<uint32_t> buckets;
  uint32_t* raw = nullptr;
  const BucketLayout layout = CountingSort(
      num_tets, num_points,
      [&](int64_t t, auto add) {
        new_edges_of(t, [&](uint32_t v, const uint32_t*, uint32_t n) { add(v, n); });
      },
      [&](uint64_t total) {
        buckets.resize(total);
        raw = buckets.data();
      },
      [&](int64_t t, auto slot) {
        new_edges_of(t, [&](uint32_t v, const uint32_t* ends, uint32_t n) {
          std::copy_n(ends, n, raw + slot(v, n));
        });
      });
  const auto& start = layout.start;
  const FillLater<uint32_t> unique_count = SortUniqueBuckets(raw, layout, num_points);
  // The edges of the mesh before that were not split, per old vertex.
  FillLater<uint32_t> kept(old_points);
  ForEachBlock(old_points, [&](int64_t, int64_t begin, int64_t end) {
    for (int64_t v = begin; v < end; ++v) {
      uint32_t k = 0;
      for (uint32_t e = before.first[v]; e < before.first[v + 1]; ++e) k += split[e] == 0;
      kept[v] = k;
    }
  });
  EdgeTable table;
  table.first.resize(num_points + 1);
  uint32_t edges = 0;
  for (int64_t v = 0; v < num_points; ++v) {
    table.first[v] = edges;
    edges += (v < old_points ? kept[v] : 0) + unique_count[v];
  }
  table.first[num_points] = edges;
  table.second.resize(edges);
  if (remap != nullptr) remap->resize(before.second.size());
  ForEachBlock(num_points, [&](int64_t, int64_t begin, int64_t end) {
    for (int64_t v = begin; v < end; ++v) {
      uint32_t* out = table.second.data() + table.first[v];
      if (v < old_points) {
        for (uint32_t e = before.first[v]; e < before.first[v + 1]; ++e) {
          if (split[e] != 0) continue;
          if (remap != nullptr) (*remap)[e] = static_cast<uint32_t>(out - table.second.data());
          *out++ = before.second[e];
        }
      }
      std::copy_n(raw + start[v], unique_count[v], out);
    }
  });
  return table;
}

namespace {

// The ids of a tet's six edges, in kTetEdges order.
inline void LookUpTetEdges(const Tet& tet, const uint32_t* first, const uint32_t* second,
                           std::array<uint32_t, 6>& out) {
  // The bucket of v[i] is sorted and holds v[i+1..3]: the id of edge (v[i], v[j]) is the
  // bucket's start plus the number of its entries below v[j]. Counting over the whole bucket,
  // without a branch on the data, took 0.35 s where stopping at each target took 0.45 s (3.95 M
  // tets of a refined T1 brain mesh, one thread, 2026-11-24): the early exits were
  // mispredicted, and a bucket holds about seven entries.
  const SortedTet s = SortTet(tet);
  for (int i = 0; i < 3; ++i) {
    const uint32_t b = first[s.v[i]];
    const uint32_t e = first[s.v[i] + 1];
    uint32_t below1 = 0, below2 = 0, below3 = 0;
    for (uint32_t k = b; k < e; ++k) {
      const uint32_t x = second[k];
      below1 += x < s.v[1];
      below2 += x < s.v[2];
      below3 += x < s.v[3];
    }
    const uint32_t below[4] = {0, below1, below2, below3};
    for (int j = i + 1; j < 4; ++j) out[EdgeIndex(s.local[i], s.local[j])] = b + below[j];
  }
}

}  // namespace

void AddTetEdges(const std::vector<Tet>& tets, EdgeTable* table) {
  const int64_t num_tets = static_cast<int64_t>(tets.size());
  // An array passed in (refine.cc passes the iteration before's) is refilled in place.
  ResizeForRefill(table->tet_edges, static_cast<size_t>(num_tets));
  const uint32_t* first = table->first.data();
  const uint32_t* second = table->second.data();
  ForEachBlock(num_tets, [&](int64_t, int64_t begin, int64_t end) {
    for (int64_t t = begin; t < end; ++t)
      LookUpTetEdges(tets[t], first, second, table->tet_edges[t]);
  });
}

void UpdateTetEdges(const std::vector<Tet>& tets, const TetSuccession& succession,
                    const FillLater<uint32_t>& remap, EdgeTable* table) {
  auto& te = table->tet_edges;
  const int64_t old_tets = static_cast<int64_t>(succession.children.size());
  const int64_t new_tets = static_cast<int64_t>(tets.size());
  if (static_cast<int64_t>(te.size()) != old_tets) return AddTetEdges(tets, table);
  const uint32_t* first = table->first.data();
  const uint32_t* second = table->second.data();
  // Writes old tet t's entries from new position `out` of `dest`: a kept tet's edges renamed
  // (`old` gives them; read only for a kept tet), or its children's looked up.
  const auto place = [&](int64_t t, int64_t out, auto old,
                         FillLater<std::array<uint32_t, 6>>& dest) {
    const int children = succession.children[t];
    if (children == 0) {
      const std::array<uint32_t, 6> edges = old();
      for (int k = 0; k < 6; ++k) dest[out][k] = remap[edges[k]];
      return;
    }
    for (int i = 0; i < children; ++i) LookUpTetEdges(tets[out + i], first, second, dest[out + i]);
  };
  const auto new_count = [&](int64_t t) { return std::max<int64_t>(1, succession.children[t]); };
  if (new_tets - old_tets > old_tets / 8 || te.capacity() < static_cast<size_t>(new_tets)) {
    // Into a new array, as AddTetEdges would allocate one here anyway; the old array lives until
    // the new one is written.
    FillLater<std::array<uint32_t, 6>> out_array;
    ResizeForRefill(out_array, static_cast<size_t>(new_tets));
    ForEachBlock(old_tets, [&](int64_t b, int64_t begin, int64_t end) {
      int64_t out = succession.block_start[b];
      for (int64_t t = begin; t < end; ++t) {
        const auto old = [&] { return te[t]; };
        place(t, out, old, out_array);
        out += new_count(t);
      }
    });
    te = std::move(out_array);
    return;
  }
  // Old tet t's entries move to its new position, at or after t: walked backwards, each chunk
  // of old tets overwrites only entries it has read already, except the first entries of its
  // own range, which the chunks before it may overwrite (they write below the chunk's first new
  // position). Those are saved first; there are at most as many as the mesh grew by.
  const int64_t blocks = BlockCount(old_tets);
  const int chunks = ChunkCount(old_tets);
  const int64_t blocks_per_chunk = (blocks + chunks - 1) / std::max(chunks, 1);
  const auto chunk_begin = [&](int64_t c) {
    return std::min(blocks, c * blocks_per_chunk) * kBlockSize;
  };
  const auto new_position = [&](int64_t old_begin) {
    return old_begin >= old_tets ? new_tets : succession.block_start[old_begin / kBlockSize];
  };
  std::vector<std::vector<std::array<uint32_t, 6>>> saved(chunks);
  for (int c = 0; c < chunks; ++c) {
    const int64_t a = std::min(chunk_begin(c), old_tets);
    const int64_t b = std::min(chunk_begin(c + 1), old_tets);
    const int64_t until = std::min(b, new_position(a));
    if (until > a) saved[c].assign(te.begin() + a, te.begin() + until);
  }
  te.resize(static_cast<size_t>(new_tets));  // within capacity: the entries stay where they are
  ForEachChunk(chunks, chunks, [&](int c, int64_t, int64_t) {
    const int64_t a = std::min(chunk_begin(c), old_tets);
    const int64_t b = std::min(chunk_begin(c + 1), old_tets);
    const int64_t saved_until = a + static_cast<int64_t>(saved[c].size());
    int64_t out = new_position(b);
    for (int64_t t = b - 1; t >= a; --t) {
      out -= new_count(t);
      const auto old = [&] { return t < saved_until ? saved[c][t - a] : te[t]; };
      place(t, out, old, te);
    }
  });
}

}  // namespace tetrefine
