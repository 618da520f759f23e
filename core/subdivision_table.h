#pragma once

#include <array>
#include <cstdint>

#include "core/configuration.h"
#include "core/tet_topology.h"
#include "core/volume.h"

namespace tetrefine {

// The paper's 64-entry lookup table (section 4): for each split pattern, its configuration and
// the order in which the tet's corners map onto that configuration's canonical corners
// (canonical corner i is local corner order[i]).
struct PatternEntry {
  Configuration configuration;
  std::array<uint8_t, 4> order;
};
const std::array<PatternEntry, 64>& PatternTable();

// The split pattern each configuration is written for (canonical corner labels).
uint32_t CanonicalPattern(Configuration c);

// A subdivision key packs everything the children of a tet depend on:
// clang-format off
//   bits 0-5    split pattern: bit e set when edge kTetEdges[e] is split
//   bits 6-9    face diagonals: bit 6 + f for face f with exactly two split edges, the bit as
//               FaceQuadOf defines it
//   bits 10-11  interior diagonal (an index into kOppositeEdgePairs) of configurations 4b, 5
//               and 6, whose interior quadrilateral or octahedron is free
// clang-format on
// Only the pattern is topology; the other bits are decided from geometry by SubdivisionKey (the
// faces by ChooseFirstDiagonal).
inline constexpr int kNumSubdivisionKeys = 1 << 12;

// Children of one key, in local point indices (tet_topology.h), positively oriented whenever the
// parent is. steiner_of lists the 6 prism points whose centroid is the Steiner point.
struct SubdivisionEntry {
  bool valid = false;
  Configuration configuration = Configuration::k0;
  bool steiner = false;
  uint8_t tet_count = 0;
  std::array<uint8_t, 6> steiner_of{};
  std::array<std::array<uint8_t, 4>, 11> tets{};
};

// The table, built and verified on first use (thread-safe). Aborts if any entry fails to tile
// its parent: that would be a programming error, and tests/core exercise every entry.
const std::array<SubdivisionEntry, kNumSubdivisionKeys>& SubdivisionTable();

// The face rule, from the face's own data only: of the diagonals (a0, a1) and (b0, b1) of a
// quadrilateral, true when (a0, a1) is chosen: the shorter one; on exactly equal lengths the one
// through the lexicographically smallest (x, then y, then z) of the four points. Two tets sharing
// the face pass the same points, so they always agree, whatever their vertex numbering.
bool ChooseFirstDiagonal(const Vec3& a0, const Vec3& a1, const Vec3& b0, const Vec3& b1);

// Face f of a tet with split `pattern` has exactly two split edges, meeting at corner A, with
// other corners B < C (local order). Its quadrilateral (B, C, m_AC, m_AB) is split by
// (B, m_AC) when the bit is 0 and by (C, m_AB) when it is 1.
struct FaceQuad {
  bool has_quad = false;
  int a = 0, b = 0, c = 0;  // local corners
};
FaceQuad FaceQuadOf(uint32_t pattern, int face);

// The key of a tet with split `pattern` whose local points 0..9 are at `points` (midpoints of
// unsplit edges are not read).
uint32_t SubdivisionKey(uint32_t pattern, const std::array<Vec3, 10>& points);

// The Steiner point of Algorithm 1: the centroid of a prism's six points, summed in
// lexicographic order of the points so that its bits do not depend on vertex numbering.
Vec3 SteinerPoint(std::array<Vec3, 6> points);

// The local points 0..10 of a tet with `corners` under `entry` (midpoints of all six edges; the
// Steiner point when the entry has one). For tests and tools that subdivide one tet.
std::array<Vec3, kNumLocalPoints> LocalPoints(const std::array<Vec3, 4>& corners,
                                              const SubdivisionEntry& entry);

}  // namespace tetrefine
