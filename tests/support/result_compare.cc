#include "tests/support/result_compare.h"

#include <bit>
#include <cstdint>
#include <cstring>

#include "gtest/gtest.h"

namespace tetrefine::testing {
namespace {

// Bit patterns, so that -0.0 != 0.0 and NaN == NaN: "identical" means identical.
template <typename T>
bool SameBits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

void ExpectSameDouble(double expected, double actual, const char* what) {
  EXPECT_EQ(std::bit_cast<uint64_t>(expected), std::bit_cast<uint64_t>(actual))
      << what << ": expected " << expected << ", got " << actual;
}

void ExpectSameQuality(const QualityStats& e, const QualityStats& a, const char* what) {
  ExpectSameDouble(e.min, a.min, what);
  ExpectSameDouble(e.mean, a.mean, what);
  EXPECT_EQ(e.count, a.count) << what;
}

}  // namespace

void ExpectSameMesh(const Mesh& expected, const Mesh& actual) {
  EXPECT_EQ(expected.points.size(), actual.points.size());
  EXPECT_EQ(expected.tets.size(), actual.tets.size());
  EXPECT_TRUE(SameBits(expected.points, actual.points)) << "points differ";
  EXPECT_TRUE(SameBits(expected.tets, actual.tets)) << "tets differ";
  EXPECT_TRUE(SameBits(expected.values, actual.values)) << "values differ";
  EXPECT_EQ(expected.labels, actual.labels) << "labels differ";
}

void ExpectSameStats(const IterationStats& e, const IterationStats& a) {
  EXPECT_EQ(e.iteration, a.iteration);
  EXPECT_EQ(e.initial_tets, a.initial_tets);
  EXPECT_EQ(e.final_tets, a.final_tets);
  EXPECT_EQ(e.tets_with_error, a.tets_with_error);
  EXPECT_EQ(e.edges, a.edges);
  EXPECT_EQ(e.split_edges, a.split_edges);
  EXPECT_EQ(e.short_edges_kept, a.short_edges_kept);
  ExpectSameDouble(e.max_error, a.max_error, "max_error");
  ExpectSameDouble(e.mean_error, a.mean_error, "mean_error");
  EXPECT_EQ(e.configurations, a.configurations);
  EXPECT_EQ(e.schonhardt_prisms, a.schonhardt_prisms);
  ExpectSameDouble(e.max_segment_error, a.max_segment_error, "max_segment_error");
  EXPECT_EQ(e.closure_edges, a.closure_edges);
  EXPECT_EQ(e.guard_edges, a.guard_edges);
  EXPECT_EQ(e.other_tilings, a.other_tilings);
  EXPECT_EQ(e.failing_tets, a.failing_tets);
  ExpectSameQuality(e.quality, a.quality, "quality");
}

void ExpectSameResult(const RefineResult& e, const RefineResult& a) {
  ExpectSameMesh(e.mesh, a.mesh);
  EXPECT_TRUE(SameBits(e.tet_iteration, a.tet_iteration)) << "tet_iteration differs";
  EXPECT_TRUE(SameBits(e.tet_quality, a.tet_quality)) << "tet_quality differs";
  EXPECT_EQ(e.tet_parent, a.tet_parent) << "tet_parent differs";
  ExpectSameDouble(e.certified_max_error, a.certified_max_error, "certified_max_error");
  ASSERT_EQ(e.iterations.size(), a.iterations.size());
  for (size_t i = 0; i < e.iterations.size(); ++i)
    ExpectSameStats(e.iterations[i], a.iterations[i]);
  EXPECT_EQ(e.stop_reason, a.stop_reason);
  EXPECT_EQ(e.next_iteration_tets, a.next_iteration_tets);
  ExpectSameDouble(e.next_iteration_min_quality, a.next_iteration_min_quality,
                   "next_iteration_min_quality");
  ExpectSameDouble(e.final_max_error, a.final_max_error, "final_max_error");
  ExpectSameDouble(e.final_mean_error, a.final_mean_error, "final_mean_error");
  ExpectSameDouble(e.norm_coeff, a.norm_coeff, "norm_coeff");
  ExpectSameQuality(e.initial_quality, a.initial_quality, "initial_quality");
  ExpectSameQuality(e.final_quality, a.final_quality, "final_quality");
  EXPECT_EQ(e.lattice.n, a.lattice.n);
  EXPECT_EQ(e.lattice.tets_sampled, a.lattice.tets_sampled);
  EXPECT_EQ(e.lattice.points_sampled, a.lattice.points_sampled);
  ExpectSameDouble(e.lattice.max_error, a.lattice.max_error, "lattice.max_error");
  ExpectSameDouble(e.lattice.mean_error, a.lattice.mean_error, "lattice.mean_error");
  ExpectSameDouble(e.lattice.share_above_epsilon, a.lattice.share_above_epsilon,
                   "lattice.share_above_epsilon");
  ExpectSameDouble(e.lattice.volume_mean_error, a.lattice.volume_mean_error,
                   "lattice.volume_mean_error");
  ExpectSameDouble(e.lattice.volume_share_above_epsilon, a.lattice.volume_share_above_epsilon,
                   "lattice.volume_share_above_epsilon");
  EXPECT_EQ(e.tets_reoriented, a.tets_reoriented);
}

}  // namespace tetrefine::testing
