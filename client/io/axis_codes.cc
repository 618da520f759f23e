#include "client/io/axis_codes.h"

#include <cmath>

namespace tetrefine::io {

AxisCodes AxisCodesOf(const Mat3& direction) {
  constexpr char kPositive[3] = {'R', 'A', 'S'};
  constexpr char kNegative[3] = {'L', 'P', 'I'};
  AxisCodes out;
  out.codes = "???";
  // Columns to unit length: an affine's columns carry the spacing, and an anisotropic grid's
  // longest column would otherwise win over a closer but shorter one.
  Mat3 unit = direction;
  for (int column = 0; column < 3; ++column) {
    double norm = 0.0;
    for (int row = 0; row < 3; ++row) norm += unit[3 * row + column] * unit[3 * row + column];
    norm = std::sqrt(norm);
    if (norm > 0.0) {
      for (int row = 0; row < 3; ++row) unit[3 * row + column] /= norm;
    }
  }
  bool column_used[3] = {false, false, false};
  bool row_used[3] = {false, false, false};
  for (int step = 0; step < 3; ++step) {
    int best_row = -1, best_column = -1;
    double best = -1.0;
    for (int column = 0; column < 3; ++column) {
      if (column_used[column]) continue;
      for (int row = 0; row < 3; ++row) {
        if (row_used[row]) continue;
        const double a = std::abs(unit[3 * row + column]);
        if (a > best) {
          best = a;
          best_row = row;
          best_column = column;
        }
      }
    }
    column_used[best_column] = true;
    row_used[best_row] = true;
    out.codes[best_column] =
        direction[3 * best_row + best_column] < 0.0 ? kNegative[best_row] : kPositive[best_row];
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
