#pragma once

#include <string>
#include <vector>

namespace tetrefine::cli {

// Rows of cells as aligned text: columns right-aligned (the first one left-aligned when
// `first_left`), each as wide as its widest cell, two spaces apart, lines indented by 2 spaces.
std::string FormatTable(const std::vector<std::vector<std::string>>& rows, bool first_left = false);

}  // namespace tetrefine::cli
