#pragma once

#include <cstdint>

namespace tetrefine::render {

struct Rgb {
  uint8_t r = 0, g = 0, b = 0;
  bool operator==(const Rgb&) const = default;
};

// Value panels (the volume and the mesh's interpolation): viridis, dark blue at t = 0 to yellow
// at t = 1. Perceptually uniform and readable in grey, so equal value steps look equal.
// t outside [0, 1] is clamped; NaN gives kNoMeshColour.
Rgb ValueColour(double t);

// The discrepancy panel: inferno, black at t = 0 (no discrepancy) through red to pale yellow at
// t = 1, so the eye goes to where the mesh is wrong. Clamped like ValueColour.
Rgb DiscrepancyColour(double t);

// Pixels no tet covers. White: neither colour map uses it.
inline constexpr Rgb kNoMeshColour{255, 255, 255};

}  // namespace tetrefine::render
