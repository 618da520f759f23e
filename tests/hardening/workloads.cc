#include "tests/hardening/workloads.h"

#include <cstring>

#include "tests/support/geometry.h"
#include "wire/conversion.h"

namespace tetrefine::hardening {
namespace {

using ::tetrefine::testing::FiveTetMesh;
using ::tetrefine::testing::TestSlab;
using ::tetrefine::testing::TestVolume;

template <typename T>
bool SameBits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

Workload Make(std::string name, Volume volume, Mesh mesh, double epsilon, int max_iterations) {
  Workload w{
      .name = std::move(name), .volume = std::move(volume), .mesh = std::move(mesh), .options = {}};
  w.options.refine.epsilon = epsilon;
  w.options.refine.max_iterations = max_iterations;
  w.options.refine.lattice_n = 4;
  return w;
}

}  // namespace

const std::vector<Workload>& SmallWorkloads() {
  static const auto* const workloads = [] {
    auto* out = new std::vector<Workload>();
    out->push_back(Make("float64", TestVolume({10, 10, 10}),
                        FiveTetMesh({1.0, 1.0, 1.0}, {8.0, 8.0, 8.0}, {2, 2, 2}), 0.05, 3));
    out->push_back(Make("int16", TestVolume({14, 14, 14}, VoxelType::kInt16),
                        FiveTetMesh({1.0, 1.0, 1.0}, {12.0, 12.0, 12.0}, {3, 3, 3}), 0.03, 3));
    Workload slab =
        Make("float32-slab", TestSlab({20, 20, 20}, {2, 2, 2}, {13, 13, 13}, VoxelType::kFloat32),
             FiveTetMesh({3.0, 3.0, 3.0}, {11.0, 11.0, 11.0}, {2, 2, 2}), 0.05, 4);
    slab.options.refine.norm_coeff = 3.0;  // the whole volume's range, as a slab's sender passes it
    out->push_back(std::move(slab));
    Workload values = Make("uint8-values-normalize", TestVolume({12, 12, 12}, VoxelType::kUint8),
                           FiveTetMesh({1.0, 1.0, 1.0}, {10.0, 10.0, 10.0}, {2, 1, 2}), 0.04, 3);
    for (size_t i = 0; i < values.mesh.points.size(); ++i) {
      values.mesh.values.push_back(values.volume.Sample(values.mesh.points[i]) + 0.5);
    }
    for (size_t t = 0; t < values.mesh.tets.size(); t += 3) {
      std::swap(values.mesh.tets[t][2], values.mesh.tets[t][3]);
    }
    values.options.refine.orientation = OrientationPolicy::kNormalize;
    out->push_back(std::move(values));
    return out;
  }();
  return *workloads;
}

const Workload& HeavyWorkload() {
  static const Workload* const heavy = [] {
    auto* w = new Workload{.name = "heavy",
                           .volume = TestVolume({64, 64, 64}),
                           .mesh = FiveTetMesh({1.0, 1.0, 1.0}, {61.0, 61.0, 61.0}, {30, 30, 30}),
                           .options = {}};
    w->options.refine.epsilon = 1e-6;
    w->options.refine.max_iterations = 4;
    w->options.SetMaxTets(20'000'000);
    // Then a lattice check of every output tet at order 12: ~2e9 samples, a minute of CPU.
    w->options.refine.lattice_n = 12;
    w->options.refine.lattice_max_tets = 0;
    w->options.skip_final_mesh = true;
    return w;
  }();
  return *heavy;
}

Workload BigResultWorkload() {
  Workload w = HeavyWorkload();
  w.name = "big-result";
  w.options.refine.max_iterations = 1;
  w.options.refine.lattice_n = 0;
  w.options.skip_final_mesh = false;
  return w;
}

Workload TinyEpsilon() {
  Workload w = SmallWorkloads()[1];
  w.name = "tiny-epsilon";
  w.options.refine.epsilon = 1e-12;
  w.options.refine.max_iterations = 16;
  w.options.refine.min_edge_length = 0.0;
  w.options.refine.lattice_n = 0;
  w.options.skip_final_mesh = true;
  return w;
}

RefineResult CoreResult(const Workload& w, const wire::ServiceLimits& limits) {
  absl::StatusOr<RefineResult> result =
      Refine(w.volume, w.mesh, wire::ToCoreOptions(w.options, limits));
  if (!result.ok()) return {};
  return *std::move(result);
}

std::string ResultDifference(const RefineResult& e, const RefineResult& a) {
  std::string out;
  auto check = [&out](bool same, const char* what) {
    if (!same) out += std::string(out.empty() ? "" : ", ") + what;
  };
  check(SameBits(e.mesh.points, a.mesh.points), "points");
  check(SameBits(e.mesh.tets, a.mesh.tets), "tets");
  check(SameBits(e.mesh.values, a.mesh.values), "values");
  check(SameBits(e.tet_iteration, a.tet_iteration), "tet_iteration");
  check(SameBits(e.tet_quality, a.tet_quality), "tet_quality");
  check(e.iterations.size() == a.iterations.size(), "iteration count");
  check(e.stop_reason == a.stop_reason, "stop_reason");
  check(std::memcmp(&e.lattice.max_error, &a.lattice.max_error, sizeof(double)) == 0,
        "lattice.max_error");
  return out;
}

}  // namespace tetrefine::hardening
