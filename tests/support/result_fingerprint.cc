#include "tests/support/result_fingerprint.h"

#include <cstring>

namespace tetrefine::testing {
namespace {

class Fnv {
 public:
  void Bytes(const void* data, size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < n; ++i) {
      h_ ^= p[i];
      h_ *= 1099511628211ull;
    }
  }
  template <typename T>
  void Vector(const std::vector<T>& v) {
    const uint64_t n = v.size();
    Bytes(&n, sizeof n);
    if (!v.empty()) Bytes(v.data(), v.size() * sizeof(T));
  }
  template <typename T>
  void Value(const T& v) {
    Bytes(&v, sizeof v);
  }
  uint64_t hash() const { return h_; }

 private:
  uint64_t h_ = 1469598103934665603ull;
};

}  // namespace

uint64_t ResultFingerprint(const RefineResult& r) {
  Fnv f;
  f.Vector(r.mesh.points);
  f.Vector(r.mesh.tets);
  f.Vector(r.mesh.values);
  f.Vector(r.mesh.labels);
  f.Vector(r.tet_iteration);
  f.Vector(r.tet_quality);
  for (const IterationStats& s : r.iterations) {
    f.Value(s.initial_tets);
    f.Value(s.final_tets);
    f.Value(s.tets_with_error);
    f.Value(s.split_edges);
    f.Value(s.max_error);
    f.Value(s.mean_error);
    f.Bytes(s.configurations.data(), sizeof(s.configurations[0]) * s.configurations.size());
    f.Value(s.schonhardt_prisms);
  }
  f.Value(static_cast<int>(r.stop_reason));
  f.Value(r.final_max_error);
  f.Value(r.lattice.max_error);
  f.Value(r.lattice.mean_error);
  return f.hash();
}

}  // namespace tetrefine::testing
