#pragma once

// Decodes a PNG with Cairo so tests can look at the pixels a figure has.

#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "client/render/colormap.h"

namespace tetrefine::render::testing {

struct Image {
  int width = 0, height = 0;
  std::vector<Rgb> pixels;  // row-major, row 0 at the top
  Rgb At(int x, int y) const { return pixels[static_cast<size_t>(y) * width + x]; }
};

// The PNG `bytes` as RGB pixels; an error when Cairo cannot decode them.
absl::StatusOr<Image> DecodePng(const std::string& bytes);

}  // namespace tetrefine::render::testing
