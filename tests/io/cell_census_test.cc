// CellCensus: counts declared by a file's headers add up without overflowing.

#include "client/io/cell_census.h"

#include <cstdint>
#include <limits>

#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace tetrefine::io {
namespace {

using ::testing::HasSubstr;

constexpr int64_t kMax = std::numeric_limits<int64_t>::max();

// The meshb fuzzer's finding: two keywords declaring counts near 2^63 overflowed the sum (undefined
// behaviour; a negative count in the message). Sums now saturate.
TEST(IoCellCensus, HugeDeclaredCountsSaturateInsteadOfOverflowing) {
  const CellKind pyramid{"pyramid", "pyramids", CellFate::kUnsupported};
  const CellKind triangle{"triangle", "triangles", CellFate::kSkip};
  CellCensus census;
  census.Add(pyramid, kMax - 1);
  census.Add(pyramid, kMax - 1);
  census.Add(triangle, kMax);
  census.Add(triangle, 5);
  census.AddTets(kMax);
  census.AddTets(kMax);
  EXPECT_EQ(census.tets(), kMax);
  EXPECT_EQ(census.skipped(), kMax);
  const absl::Status status = census.Check("f.meshb");
  ASSERT_FALSE(status.ok());
  EXPECT_THAT(status.message(), HasSubstr("9223372036854775807 pyramids"));
  EXPECT_THAT(status.message(), HasSubstr("f.meshb"));
}

TEST(IoCellCensus, OrdinaryCountsAddUp) {
  const CellKind hexahedron{"hexahedron", "hexahedra", CellFate::kUnsupported};
  CellCensus census;
  census.Add(hexahedron, 1);
  census.Add(hexahedron, 119);
  census.Add(hexahedron, 0);
  census.Add(hexahedron, -4);  // ignored
  EXPECT_THAT(census.Check("m.vtu").message(), HasSubstr("120 hexahedra and no tetrahedra"));
}

}  // namespace
}  // namespace tetrefine::io
