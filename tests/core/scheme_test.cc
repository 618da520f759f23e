// What the schemes promise beyond conformity (refine_test.cc checks that for both): the paper
// scheme's results pinned to the bit, labels and input-tet parents carried to every child with
// each region's volume unchanged, and certified mode's bound on every tet's lattice.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <map>
#include <random>
#include <utility>

#include "core/lattice.h"
#include "core/refine.h"
#include "tests/support/geometry.h"
#include "tests/support/mesh_checks.h"
#include "tests/support/pinned_cases.h"
#include "tests/support/result_fingerprint.h"
#include "tests/support/scheme_printer.h"

namespace tetrefine {
namespace {

double TetVolume(const Mesh& m, const Tet& t) {
  return SignedVolume6(m.points[t[0]], m.points[t[1]], m.points[t[2]], m.points[t[3]]) / 6.0;
}

// The paper's scheme must not drift: these fingerprints were computed by the paper-only core
// (commit a834583, before schemes existed) on the same inputs, and the paper scheme reproduces
// them to the bit.
TEST(PaperScheme, ResultsArePinnedToTheBit) {
  const std::map<std::string, uint64_t> pinned = {
      {"sharp_blob_blocks", 0xb1771638aefbc475ull},
      {"smooth_blob_blocks", 0xce6cafd75021bd35ull},
      {"cube_blob", 0xa8586075390c818bull},
  };
  for (const testing::PinnedCase& c : testing::PinnedCases()) {
    RefineOptions o;
    o.scheme = RefineScheme::kPaper;
    o.epsilon = c.epsilon;
    o.max_iterations = c.max_iterations;
    auto r = Refine(c.volume, c.mesh, o);
    ASSERT_TRUE(r.ok()) << c.name << ": " << r.status();
    EXPECT_EQ(testing::ResultFingerprint(*r), pinned.at(c.name)) << c.name;
  }
}

class EveryScheme : public ::testing::TestWithParam<RefineScheme> {};

TEST_P(EveryScheme, LabelsAndParentsFollowEveryChildAndRegionVolumesStay) {
  for (uint64_t seed : testing::Seeds(3)) {
    SCOPED_TRACE(::testing::Message() << "seed " << seed);
    std::mt19937_64 rng(seed);
    testing::PinnedCase c = std::move(testing::PinnedCases()[seed % 2]);
    std::uniform_int_distribution<int32_t> label(-3, 3);
    c.mesh.labels.resize(c.mesh.tets.size());
    for (int32_t& l : c.mesh.labels) l = label(rng);
    RefineOptions o;
    o.scheme = GetParam();
    o.epsilon = c.epsilon;
    o.max_iterations = 5;
    o.track_parents = true;
    // Every iteration's mesh carries its labels too (what --every-iteration writes).
    int iterations_seen = 0;
    o.on_iteration = [&](const IterationStats&, const Mesh& m) {
      ++iterations_seen;
      EXPECT_EQ(m.labels.size(), m.tets.size());
    };
    auto r = Refine(c.volume, c.mesh, o);
    ASSERT_TRUE(r.ok()) << r.status();
    EXPECT_GT(iterations_seen, 0);
    ASSERT_GT(r->mesh.tets.size(), c.mesh.tets.size());
    ASSERT_EQ(r->mesh.labels.size(), r->mesh.tets.size());
    ASSERT_EQ(r->tet_parent.size(), r->mesh.tets.size());
    std::map<int32_t, double> before, after;
    std::vector<double> parent_volume(c.mesh.tets.size(), 0.0);
    for (size_t t = 0; t < c.mesh.tets.size(); ++t) {
      before[c.mesh.labels[t]] += TetVolume(c.mesh, c.mesh.tets[t]);
    }
    for (size_t t = 0; t < r->mesh.tets.size(); ++t) {
      const uint32_t parent = r->tet_parent[t];
      ASSERT_LT(parent, c.mesh.tets.size());
      EXPECT_EQ(r->mesh.labels[t], c.mesh.labels[parent]);
      const double v = TetVolume(r->mesh, r->mesh.tets[t]);
      after[r->mesh.labels[t]] += v;
      parent_volume[parent] += v;
    }
    for (const auto& [l, v] : before) EXPECT_NEAR(after[l], v, 1e-9 * v) << "label " << l;
    for (size_t t = 0; t < c.mesh.tets.size(); ++t) {
      const double v = TetVolume(c.mesh, c.mesh.tets[t]);
      EXPECT_NEAR(parent_volume[t], v, 1e-9 * v) << "input tet " << t;
    }
  }
}

TEST_P(EveryScheme, LabelsOfTheWrongLengthAreRefused) {
  testing::PinnedCase c = std::move(testing::PinnedCases()[1]);
  c.mesh.labels = {1, 2, 3};
  RefineOptions o;
  o.scheme = GetParam();
  auto r = Refine(c.volume, c.mesh, o);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("mesh.labels"), std::string::npos) << r.status();
}

TEST_P(EveryScheme, CertifiedModeBoundsEveryTetsLattice) {
  for (const testing::PinnedCase& c : testing::PinnedCases()) {
    SCOPED_TRACE(c.name);
    RefineOptions o;
    o.scheme = GetParam();
    o.certify = true;
    o.epsilon = 0.1;
    o.max_iterations = 32;
    o.min_quality = 0.0;
    o.on_iteration = [&](const IterationStats& s, const Mesh& m) {
      EXPECT_EQ(testing::ConformityProblem(c.mesh, m), "") << "iteration " << s.iteration;
    };
    auto r = Refine(c.volume, c.mesh, o);
    ASSERT_TRUE(r.ok()) << r.status();
    if (GetParam() == RefineScheme::kPaper && r->stop_reason != StopReason::kConverged) {
      // The paper's scheme may stop on a limit first; then nothing is certified.
      EXPECT_LT(r->certified_max_error, 0.0);
      continue;
    }
    ASSERT_EQ(r->stop_reason, StopReason::kConverged);
    const LatticeStats all = SampleLattice(c.volume, r->mesh, o.lattice_n, /*max_tets=*/0, 1,
                                           r->norm_coeff, o.epsilon, false);
    EXPECT_LE(all.max_error, o.epsilon);
    EXPECT_EQ(r->certified_max_error, all.max_error);
    EXPECT_LE(r->final_max_error, o.epsilon);
  }
}

bool SameBits(double a, double b) { return std::memcmp(&a, &b, sizeof(double)) == 0; }

// Certified mode's final verification reads the lattices its checks measured instead of sampling
// the tets again: the statistics must be the bits a fresh SampleLattice gives, whether the call
// converged or stopped on its budget (failing tets sampled afresh), over every tet or a sample,
// with the input as given or with every tet reoriented (the corners, and so the points, in
// another order).
TEST_P(EveryScheme, CertifiedVerificationEqualsAFreshLatticeToTheBit) {
  int stopped_early = 0;
  for (const testing::PinnedCase& c : testing::PinnedCases()) {
    for (bool reoriented : {false, true}) {
      for (int64_t max_tets : {int64_t{1'000'000}, int64_t{3'000}}) {
        for (int64_t lattice_max_tets : {int64_t{200'000}, int64_t{500}}) {
          SCOPED_TRACE(::testing::Message()
                       << c.name << (reoriented ? " reoriented" : "") << " max_tets " << max_tets
                       << " lattice_max_tets " << lattice_max_tets);
          Mesh mesh = c.mesh;
          RefineOptions o;
          if (reoriented) {
            for (Tet& t : mesh.tets) std::swap(t[2], t[3]);
            o.orientation = OrientationPolicy::kNormalize;
          }
          o.scheme = GetParam();
          o.certify = true;
          o.epsilon = 0.05;
          o.max_iterations = 32;
          o.min_quality = 0.0;
          o.max_tets = max_tets;
          o.lattice_max_tets = lattice_max_tets;
          auto r = Refine(c.volume, mesh, o);
          ASSERT_TRUE(r.ok()) << r.status();
          if (r->stop_reason != StopReason::kConverged) ++stopped_early;
          const LatticeStats fresh =
              SampleLattice(c.volume, r->mesh, o.lattice_n, o.lattice_max_tets, o.lattice_seed,
                            r->norm_coeff, o.epsilon, false);
          EXPECT_EQ(r->lattice.tets_sampled, fresh.tets_sampled);
          EXPECT_EQ(r->lattice.points_sampled, fresh.points_sampled);
          EXPECT_TRUE(SameBits(r->lattice.max_error, fresh.max_error));
          EXPECT_TRUE(SameBits(r->lattice.mean_error, fresh.mean_error));
          EXPECT_TRUE(SameBits(r->lattice.share_above_epsilon, fresh.share_above_epsilon));
          EXPECT_TRUE(SameBits(r->lattice.volume_mean_error, fresh.volume_mean_error));
          EXPECT_TRUE(
              SameBits(r->lattice.volume_share_above_epsilon, fresh.volume_share_above_epsilon));
        }
      }
    }
  }
  // The budget of 3000 tets stops some calls with tets above epsilon, whose lattices the
  // verification must sample itself.
  EXPECT_GT(stopped_early, 0);
}

TEST(LongestEdgeScheme, ConvergesWithBoundedQualityOnEveryPinnedCase) {
  for (const testing::PinnedCase& c : testing::PinnedCases()) {
    for (double epsilon : {0.1, 0.05}) {
      SCOPED_TRACE(::testing::Message() << c.name << " epsilon " << epsilon);
      RefineOptions o;
      o.scheme = RefineScheme::kLongestEdge;
      o.epsilon = epsilon;
      o.max_iterations = 32;
      auto r = Refine(c.volume, c.mesh, o);
      ASSERT_TRUE(r.ok()) << r.status();
      EXPECT_EQ(r->stop_reason, StopReason::kConverged);
      EXPECT_LE(r->final_max_error, epsilon);
      EXPECT_GE(r->final_quality.min, 0.3 * r->initial_quality.min);
      EXPECT_GE(r->final_quality.mean, 0.8 * r->initial_quality.mean);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Schemes, EveryScheme,
                         ::testing::Values(RefineScheme::kPaper, RefineScheme::kLongestEdge),
                         [](const ::testing::TestParamInfo<RefineScheme>& info) {
                           return info.param == RefineScheme::kPaper ? "Paper" : "LongestEdge";
                         });

}  // namespace
}  // namespace tetrefine
