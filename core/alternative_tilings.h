#pragma once

#include <array>
#include <cstdint>

#include "core/subdivision_table.h"
#include "core/volume.h"

// The other ways to cut a tet with a given subdivision key. The paper's table (Table 1) gives one
// tiling per key; for some keys the same boundary triangles (the faces, each triangulated from
// its own data) admit other Steiner-free tilings of the inside. Which ones exist depends only on
// the key: orientation and containment of the tet's corners and midpoints are affine invariants,
// so the tilings found on one reference tet are the tilings of every tet. The longest-edge scheme
// cuts each tet by the tiling whose worst child is best; the paper's scheme keeps the table's.
namespace tetrefine {

// Tilings beyond the table's, per key, at most (measured over every key: configuration 6 has 2,
// 3c, 4a, 4b and 5 at most 1, the others none).
inline constexpr int kMaxAlternativeTilings = 2;

// A tiling key: bits 0-11 the subdivision key, bits 12-13 which tiling (0: the table's; i >= 1:
// AlternativeTilings(key)[i - 1]). Fits the uint16_t Subdivide keeps per tet.
inline constexpr int kTilingShift = 12;
inline constexpr int kNumTilingKeys = kNumSubdivisionKeys << 2;
// Not a tiling key: for caches of BestTiling's answers (uint16_t entries).
inline constexpr uint16_t kUnknownTiling = 0xffff;
static_assert(kNumTilingKeys <= kUnknownTiling);

struct AlternativeTilings {
  int count = 0;
  // Children in local point indices (tet_topology.h), positively oriented whenever the parent
  // is; no Steiner point. configuration is the key's; tet_count may differ from Table 1's (3c has
  // a 4-tet tiling, 4a a 5-tet one).
  std::array<SubdivisionEntry, kMaxAlternativeTilings> entries{};
};

// Per subdivision key, found once on first use (thread-safe) by enumerating every tiling of the
// table entry's boundary whose tets use only the tet's corners and split-edge midpoints; each is
// checked with IsTiling. Keys with a Steiner point, and invalid keys, have none.
const std::array<AlternativeTilings, kNumSubdivisionKeys>& AlternativeTilingTable();

// The entry of a tiling key.
const SubdivisionEntry& TilingEntry(uint32_t tiling_key);

// The tiling key of a tet with subdivision key `key` and corners `corners` (positively oriented):
// the tiling whose worst child has the largest mean ratio. Ties (regular meshes have them) go
// by geometry only, never by numbering: fewer tets, then the table's tiling, then the
// lexicographically smallest sorted list of children (each child as its sorted corner points).
uint32_t BestTiling(uint32_t key, const std::array<Vec3, 4>& corners);

// BestTiling's answer with the mean ratio of its worst child (at most 1). Each child is measured
// with its points in lexicographic order, so `worst` is the same bits under every numbering of
// the corners, and callers may rank tets' tilings by it (the guard's remedy, core/edge_marking.h).
struct TilingChoice {
  uint32_t tiling = 0;  // a tiling key
  double worst = 0.0;   // mean ratio of its worst child
};
TilingChoice ChooseTiling(uint32_t key, const std::array<Vec3, 4>& corners);

}  // namespace tetrefine
