#pragma once

#include <array>
#include <cstdint>

namespace tetrefine {

// Local numbering of the points of a tet being subdivided:
//   0..3  its corners, in the tet's vertex order
//   4..9  the midpoints of its edges, in kTetEdges order (4 + edge index)
//   10    the Steiner point of a Schönhardt prism, when there is one
inline constexpr std::array<std::array<int, 2>, 6> kTetEdges = {
    {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}}};
inline constexpr int kNumLocalPoints = 11;
inline constexpr int kSteinerLocal = 10;

// Face f is the face opposite corner f; its corners in increasing order.
inline constexpr std::array<std::array<int, 3>, 4> kTetFaces = {
    {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}}};

// Index in kTetEdges of the edge joining corners a != b.
constexpr int EdgeIndex(int a, int b) {
  if (a > b) {
    const int t = a;
    a = b;
    b = t;
  }
  return a == 0 ? b - 1 : (a == 1 ? b + 1 : 5);
}

// Local point index of the midpoint of edge (a, b).
constexpr int MidpointLocal(int a, int b) { return 4 + EdgeIndex(a, b); }

// The three octahedron diagonals, joining midpoints of opposite edges: (01,23), (02,13), (03,12).
inline constexpr std::array<std::array<int, 2>, 3> kOppositeEdgePairs = {{{0, 5}, {1, 4}, {2, 3}}};

// Bit of edge e in a 6-bit split pattern (paper Figure 13: entry 25 = 011001 splits 01, 12, 13).
constexpr uint32_t EdgeBit(int e) { return 1u << e; }

}  // namespace tetrefine
