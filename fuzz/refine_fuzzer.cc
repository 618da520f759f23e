// libFuzzer target: the core on small arbitrary inputs. The bytes decode into a tiny volume (or
// slab), a mesh of a few tets (either a jittered box of 5 tets a cell, or arbitrary points and
// tets) and options; whatever Refine accepts must come out as a valid refinement: every tet
// positive, no face in more than two tets nor two tets on one side of a face (CheckFaces), the
// total volume preserved to 1e-9 relative, per-tet arrays as long as the tets, every vertex
// finite. Iterations and tets are kept small so that an input runs in milliseconds.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <optional>
#include <vector>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "core/mesh_validation.h"
#include "core/refine.h"
#include "fuzz/fuzz_support.h"

namespace tetrefine::fuzz {
namespace {

template <typename T, size_t N>
T Pick(ByteSource& in, const std::array<T, N>& choices) {
  return choices[in.Byte() % N];
}

// nullopt for a grid Volume::Create refuses as such: one whose sample positions float64 cannot
// tell apart (spacing 1e-150 at origin 1e300), whose index map overflows. Such grids were once
// accepted with an infinite boundary tolerance, every point "inside".
std::optional<Volume> DecodeVolume(ByteSource& in) {
  GridGeometry grid;
  Index3 lo, hi;
  const bool slab = in.Byte() & 1;
  for (int a = 0; a < 3; ++a) {
    grid.dims[a] = in.Int(2, 6);
    grid.spacing[a] = Pick(in, std::array{1.0, 0.5, 2.0, 0.3, 3.7, 1e-3, 1e3, 1e-150, 1e150});
    grid.origin[a] = Pick(in, std::array{0.0, -1.0, 10.5, -1000.0, 1e6, 0.25, -1e200, 1e300});
    lo[a] = 0;
    hi[a] = grid.dims[a];
    if (slab && grid.dims[a] > 2) {
      lo[a] = in.Int(0, static_cast<int>(grid.dims[a] - 2));
      hi[a] = in.Int(static_cast<int>(lo[a] + 2), static_cast<int>(grid.dims[a]));
    }
  }
  const VoxelType type = static_cast<VoxelType>(in.Byte() % 6);
  const bool raw_floats = in.Byte() & 1;
  const int64_t count = (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]);
  std::vector<std::byte> data;
  for (int64_t i = 0; i < count; ++i) {
    if ((type == VoxelType::kFloat32 || type == VoxelType::kFloat64) && !raw_floats) {
      // Small integers make ties and flat regions, which raw bits almost never do.
      const double v = static_cast<int8_t>(in.Byte());
      if (type == VoxelType::kFloat32) {
        const float f = static_cast<float>(v);
        const auto* b = reinterpret_cast<const std::byte*>(&f);
        data.insert(data.end(), b, b + sizeof(f));
      } else {
        const auto* b = reinterpret_cast<const std::byte*>(&v);
        data.insert(data.end(), b, b + sizeof(v));
      }
      continue;
    }
    for (size_t k = 0; k < VoxelSize(type); ++k) data.push_back(std::byte{in.Byte()});
  }
  absl::StatusOr<Volume> volume = Volume::Create(grid, lo, hi, type, std::move(data));
  if (!volume.ok()) {
    // Raw float bits may be NaN or infinite; fall back to zeros rather than losing the input.
    std::vector<std::byte> zeros(static_cast<size_t>(count) * VoxelSize(type));
    volume = Volume::Create(grid, lo, hi, type, std::move(zeros));
  }
  if (!volume.ok() && absl::StrContains(volume.status().message(), "volume grid: ")) {
    return std::nullopt;
  }
  TETREFINE_FUZZ_CHECK(volume.ok(), volume.status().ToString());
  return *std::move(volume);
}

// A world position at fraction f (0..1, possibly a little outside) of the slab's box on each axis.
Vec3 InBox(const Volume& volume, const std::array<double, 3>& f) {
  Vec3 p;
  for (int a = 0; a < 3; ++a) {
    const double lo = static_cast<double>(volume.lo()[a]);
    const double hi = static_cast<double>(volume.hi()[a] - 1);
    p[a] = volume.grid().origin[a] + (lo + f[a] * (hi - lo)) * volume.grid().spacing[a];
  }
  return p;
}

// The box [f0, f1] of the slab cut into cells of 5 tets with alternating parity (shared faces
// match), every vertex moved by up to `jitter` of a cell.
Mesh BoxMesh(ByteSource& in, const Volume& volume) {
  std::array<int, 3> cells;
  std::array<double, 3> f0, f1;
  for (int a = 0; a < 3; ++a) {
    cells[a] = in.Int(1, 2);
    f0[a] = in.Byte() / 1024.0;
    f1[a] = 1.0 - in.Byte() / 1024.0;
  }
  const double jitter = Pick(in, std::array{0.0, 0.0, 0.05, 0.2, 0.45});
  Mesh mesh;
  for (int k = 0; k <= cells[2]; ++k) {
    for (int j = 0; j <= cells[1]; ++j) {
      for (int i = 0; i <= cells[0]; ++i) {
        const int index[3] = {i, j, k};
        std::array<double, 3> f;
        for (int a = 0; a < 3; ++a) {
          const double d = jitter * (in.Byte() / 127.5 - 1.0) / cells[a];
          f[a] = f0[a] + (f1[a] - f0[a]) * (index[a] + d) / cells[a];
        }
        mesh.points.push_back(InBox(volume, f));
      }
    }
  }
  const int nx = cells[0] + 1, ny = cells[1] + 1;
  for (int k = 0; k < cells[2]; ++k) {
    for (int j = 0; j < cells[1]; ++j) {
      for (int i = 0; i < cells[0]; ++i) {
        uint32_t c[8];
        for (int b = 0; b < 8; ++b) {
          c[b] = static_cast<uint32_t>((i + (b & 1)) +
                                       nx * ((j + ((b >> 1) & 1)) + ny * (k + (b >> 2))));
        }
        const bool even = (i + j + k) % 2 == 0;
        const int corners[4] = {even ? 0 : 1, even ? 3 : 2, even ? 5 : 4, even ? 6 : 7};
        for (int corner : corners) {
          mesh.tets.push_back({c[corner], c[corner ^ 1], c[corner ^ 2], c[corner ^ 4]});
        }
        const int centre[4] = {even ? 1 : 0, even ? 2 : 3, even ? 4 : 5, even ? 7 : 6};
        mesh.tets.push_back({c[centre[0]], c[centre[1]], c[centre[2]], c[centre[3]]});
      }
    }
  }
  // Orientation as built is either sign; the fuzzer may leave it (testing kReject) or not.
  if (in.Byte() & 1) {
    for (Tet& t : mesh.tets) {
      if (SignedVolume6(mesh.points[t[0]], mesh.points[t[1]], mesh.points[t[2]],
                        mesh.points[t[3]]) < 0) {
        std::swap(t[2], t[3]);
      }
    }
  }
  return mesh;
}

// Points on a 1/16 lattice of the box (so that coplanar and coincident points happen) and tets
// over them.
Mesh ArbitraryMesh(ByteSource& in, const Volume& volume) {
  Mesh mesh;
  const int points = in.Int(4, 12);
  for (int i = 0; i < points; ++i) {
    std::array<double, 3> f;
    for (int a = 0; a < 3; ++a) f[a] = (in.Byte() % 19 - 1) / 16.0;
    mesh.points.push_back(InBox(volume, f));
  }
  const int tets = in.Int(1, 8);
  for (int t = 0; t < tets; ++t) {
    Tet tet;
    for (uint32_t& v : tet) v = in.Byte() % points;
    mesh.tets.push_back(tet);
  }
  return mesh;
}

RefineOptions DecodeOptions(ByteSource& in) {
  RefineOptions o;
  o.threads = 1;
  o.epsilon = Pick(in, std::array{0.5, 0.1, 0.05, 0.01, 1e-3, 1e-9});
  o.max_iterations = in.Int(0, 4);
  o.max_tets = in.Int(1, 3000);
  o.orientation = (in.Byte() & 1) ? OrientationPolicy::kNormalize : OrientationPolicy::kReject;
  o.outside = (in.Byte() & 1) ? OutsidePolicy::kClamp : OutsidePolicy::kReject;
  o.lattice_n = in.Int(0, 4);
  o.lattice_max_tets = in.Int(1, 64);
  o.lattice_seed = in.Byte();
  switch (in.Byte() % 4) {
    case 0:
      break;  // the default: 1/64 voxel
    case 1:
      o.min_edge_length = 0.0;
      break;
    case 2:
      o.min_edge_length = 1e-3;
      break;
    default:
      o.min_edge_length = 10.0;
  }
  o.min_quality = Pick(in, std::array{1e-6, 0.0, 1e-3, 0.1, 0.5});
  if (in.Byte() & 1) o.norm_coeff = Pick(in, std::array{1.0, 1e-12, 1e12, 300.0});
  return o;
}

// For triage (TETREFINE_FUZZ_VERBOSE=1): what an input decoded to and what Refine made of it.
void Describe(const Volume& volume, const Mesh& mesh, const RefineOptions& o,
              const absl::StatusOr<RefineResult>& result) {
  const GridGeometry& g = volume.grid();
  std::fprintf(stderr, "grid dims %lld %lld %lld origin %g %g %g spacing %g %g %g type %s\n",
               static_cast<long long>(g.dims[0]), static_cast<long long>(g.dims[1]),
               static_cast<long long>(g.dims[2]), g.origin[0], g.origin[1], g.origin[2],
               g.spacing[0], g.spacing[1], g.spacing[2],
               std::string(VoxelTypeName(volume.type())).c_str());
  for (const Vec3& p : mesh.points)
    std::fprintf(stderr, "point %.17g %.17g %.17g\n", p[0], p[1], p[2]);
  for (const Tet& t : mesh.tets) std::fprintf(stderr, "tet %u %u %u %u\n", t[0], t[1], t[2], t[3]);
  std::fprintf(stderr,
               "epsilon %g max_iterations %d max_tets %lld min_quality %g min_edge_length %g "
               "orientation %d outside %d\n",
               o.epsilon, o.max_iterations, static_cast<long long>(o.max_tets),
               o.min_quality.value_or(-1.0), o.min_edge_length.value_or(-1),
               static_cast<int>(o.orientation), static_cast<int>(o.outside));
  if (!result.ok()) {
    std::fprintf(stderr, "refine: %s\n", result.status().ToString().c_str());
  } else {
    std::fprintf(stderr, "refine: %zu tets, %zu iterations, stop %s\n", result->mesh.tets.size(),
                 result->iterations.size(),
                 std::string(StopReasonName(result->stop_reason)).c_str());
  }
}

double TotalVolume6(const Mesh& mesh) {
  double total = 0.0;
  for (const Tet& t : mesh.tets) {
    total += std::abs(
        SignedVolume6(mesh.points[t[0]], mesh.points[t[1]], mesh.points[t[2]], mesh.points[t[3]]));
  }
  return total;
}

void CheckRefinement(const Mesh& input, const RefineResult& result) {
  const Mesh& out = result.mesh;
  const size_t n = out.points.size();
  TETREFINE_FUZZ_CHECK(out.values.size() == n, "one value per vertex");
  TETREFINE_FUZZ_CHECK(result.tet_iteration.size() == out.tets.size(), "one iteration per tet");
  TETREFINE_FUZZ_CHECK(result.tet_quality.size() == out.tets.size(), "one quality per tet");
  TETREFINE_FUZZ_CHECK(n >= input.points.size(), "vertices were lost");
  for (size_t i = 0; i < n; ++i) {
    for (int a = 0; a < 3; ++a) {
      TETREFINE_FUZZ_CHECK(std::isfinite(out.points[i][a]), absl::StrCat("vertex ", i));
    }
    TETREFINE_FUZZ_CHECK(std::isfinite(out.values[i]), absl::StrCat("value of vertex ", i));
  }
  for (size_t t = 0; t < out.tets.size(); ++t) {
    const Tet& q = out.tets[t];
    for (uint32_t v : q) TETREFINE_FUZZ_CHECK(v < n, absl::StrCat("tet ", t, " index"));
    const double v6 =
        SignedVolume6(out.points[q[0]], out.points[q[1]], out.points[q[2]], out.points[q[3]]);
    TETREFINE_FUZZ_CHECK(v6 > 0.0, absl::StrCat("tet ", t, " has 6V = ", v6));
  }
  const absl::Status faces = CheckFaces(out.points, out.tets);
  TETREFINE_FUZZ_CHECK(faces.ok(), faces.ToString());
  // Preserved to 1e-9 relative, plus what rounding the vertices can move: a midpoint is exact
  // only to an ulp of the coordinates' magnitude M, and moving a boundary vertex by d changes the
  // volume by about d times its faces' area. Far from the origin (M / edge length ~ 1e9) that
  // is the larger term.
  double magnitude = 0.0;
  for (const Vec3& p : out.points) {
    magnitude = std::max({magnitude, std::abs(p[0]), std::abs(p[1]), std::abs(p[2])});
  }
  double rounding = 0.0;
  for (const Tet& q : out.tets) {
    double longest2 = 0.0;
    for (int i = 0; i < 4; ++i) {
      for (int j = i + 1; j < 4; ++j) {
        const Vec3& a = out.points[q[i]];
        const Vec3& b = out.points[q[j]];
        longest2 =
            std::max(longest2, (a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                                   (a[2] - b[2]) * (a[2] - b[2]));
      }
    }
    rounding += 64.0 * std::numeric_limits<double>::epsilon() * magnitude * longest2;
  }
  const double before = TotalVolume6(input);
  const double after = TotalVolume6(out);
  TETREFINE_FUZZ_CHECK(std::abs(before - after) <= 1e-9 * before + rounding,
                       absl::StrCat("total volume changed from ", before / 6, " to ", after / 6,
                                    " (rounding allowance ", rounding / 6, ")"));
  if (result.stop_reason == StopReason::kTetBudget) {
    TETREFINE_FUZZ_CHECK(result.next_iteration_tets > 0, "a tet budget stop says how many");
  }
}

}  // namespace
}  // namespace tetrefine::fuzz

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace tetrefine;  // NOLINT: a fuzz entry point
  fuzz::ByteSource in(data, size);
  const std::optional<Volume> decoded = fuzz::DecodeVolume(in);
  if (!decoded.has_value()) return 0;
  const Volume& volume = *decoded;
  const Mesh mesh = (in.Byte() & 1) ? fuzz::ArbitraryMesh(in, volume) : fuzz::BoxMesh(in, volume);
  const RefineOptions options = fuzz::DecodeOptions(in);
  absl::StatusOr<RefineResult> result = Refine(volume, mesh, options);
  if (std::getenv("TETREFINE_FUZZ_VERBOSE") != nullptr)
    fuzz::Describe(volume, mesh, options, result);
  if (!result.ok()) {
    TETREFINE_FUZZ_CHECK(absl::IsInvalidArgument(result.status()), result.status().ToString());
    return 0;
  }
  fuzz::CheckRefinement(mesh, *result);
  return 0;
}
