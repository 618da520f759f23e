#include "client/io/axis_codes.h"

#include <cmath>

namespace tetrefine::io {

AxisCodes AxisCodesOf(const Mat3& direction) {
  constexpr char kPositive[3] = {'R', 'A', 'S'};
  constexpr char kNegative[3] = {'L', 'P', 'I'};
  AxisCodes out;
  out.codes = "???";
  // nibabel's io_orientation: each index axis in turn takes the world axis along which its
  // column is largest, among those the axes before it left. (nibabel first replaces the columns
  // by the nearest orthogonal ones; a scanner's grid has orthogonal columns already.)
  bool row_used[3] = {false, false, false};
  for (int column = 0; column < 3; ++column) {
    int best_row = -1;
    double best = -1.0;
    for (int row = 0; row < 3; ++row) {
      const double a = std::abs(direction[3 * row + column]);
      if (!row_used[row] && a > best) {
        best = a;
        best_row = row;
      }
    }
    row_used[best_row] = true;
    out.codes[column] =
        direction[3 * best_row + column] < 0.0 ? kNegative[best_row] : kPositive[best_row];
  }
  // Exact when every entry off the chosen ones is zero: each column then has a single nonzero.
  int nonzero = 0;
  for (double d : direction) nonzero += d != 0.0;
  out.exact = nonzero == 3;
  return out;
}

const char* AxisCodeWord(char code) {
  switch (code) {
    case 'R':
      return "right";
    case 'L':
      return "left";
    case 'A':
      return "anterior";
    case 'P':
      return "posterior";
    case 'S':
      return "superior";
    case 'I':
      return "inferior";
    default:
      return "?";
  }
}

}  // namespace tetrefine::io
