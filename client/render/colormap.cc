#include "client/render/colormap.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace tetrefine::render {
namespace {

using Stops = std::array<Rgb, 9>;  // the map at t = 0, 1/8, ..., 1

// matplotlib's viridis and inferno sampled at eighths of their range.
constexpr Stops kViridis = {{{68, 1, 84},
                             {71, 44, 122},
                             {59, 81, 139},
                             {44, 113, 142},
                             {33, 144, 141},
                             {39, 173, 129},
                             {92, 200, 99},
                             {170, 220, 50},
                             {253, 231, 37}}};
constexpr Stops kInferno = {{{0, 0, 4},
                             {31, 12, 72},
                             {85, 15, 109},
                             {136, 34, 106},
                             {186, 54, 85},
                             {227, 89, 51},
                             {249, 140, 10},
                             {249, 201, 50},
                             {252, 255, 164}}};

Rgb Interpolate(const Stops& stops, double t) {
  if (std::isnan(t)) return kNoMeshColour;
  t = std::clamp(t, 0.0, 1.0) * (stops.size() - 1);
  const size_t i = std::min(static_cast<size_t>(t), stops.size() - 2);
  const double f = t - static_cast<double>(i);
  const auto mix = [f](uint8_t a, uint8_t b) {
    return static_cast<uint8_t>(std::lround(a + f * (static_cast<double>(b) - a)));
  };
  return {mix(stops[i].r, stops[i + 1].r), mix(stops[i].g, stops[i + 1].g),
          mix(stops[i].b, stops[i + 1].b)};
}

}  // namespace

Rgb ValueColour(double t) { return Interpolate(kViridis, t); }

Rgb DiscrepancyColour(double t) { return Interpolate(kInferno, t); }

}  // namespace tetrefine::render
