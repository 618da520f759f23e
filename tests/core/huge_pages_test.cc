// AdviseHugePages and ReserveHuge (core/huge_pages.h): advice is only advice. Memory advised
// before or after it is written holds what was written, whatever its size or alignment, and
// ReserveHuge leaves a container with the room asked for and its contents unchanged.
#include "core/huge_pages.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <memory>
#include <random>
#include <string>
#include <vector>

namespace tetrefine {
namespace {

uint32_t Pattern(uint32_t seed, size_t i) { return static_cast<uint32_t>(seed * 2654435761u ^ i); }

TEST(HugePages, AdvisedMemoryHoldsWhatIsWrittenBeforeAndAfter) {
  std::mt19937 rng(7);
  // Sizes below, at and above the 4 MiB floor, at odd offsets into the allocation.
  for (const size_t n : {size_t{0}, size_t{1}, size_t{1} << 20, (size_t{1} << 20) + 3,
                         size_t{3} << 20, (size_t{5} << 20) + 17}) {
    const uint32_t seed = rng();
    const std::unique_ptr<uint32_t[]> buffer(new uint32_t[n + 8]);
    uint32_t* data = buffer.get() + (seed % 8);
    const size_t before = n / 2;
    for (size_t i = 0; i < before; ++i) data[i] = Pattern(seed, i);
    AdviseHugePages(data, n * sizeof(uint32_t));
    for (size_t i = before; i < n; ++i) data[i] = Pattern(seed, i);
    size_t wrong = n;
    for (size_t i = 0; i < n && wrong == n; ++i) {
      if (data[i] != Pattern(seed, i)) wrong = i;
    }
    EXPECT_EQ(wrong, n) << "n " << n << ": element " << wrong << " changed";
  }
  AdviseHugePages(nullptr, size_t{64} << 20);  // nothing to advise: no effect, no crash
}

TEST(HugePages, ReserveHugeGivesTheRoomAndKeepsTheContents) {
  for (const size_t n : {size_t{10}, size_t{3} << 20}) {
    std::vector<uint32_t> v = {1, 2, 3};
    ReserveHuge(v, n);
    EXPECT_GE(v.capacity(), n);
    EXPECT_EQ(v, (std::vector<uint32_t>{1, 2, 3}));
    const uint32_t* storage = v.data();
    v.resize(n, 9u);  // within the reserved room: no reallocation
    EXPECT_EQ(v.data(), storage);
    EXPECT_EQ(v[2], 3u);
    EXPECT_EQ(v[n - 1], 9u);

    std::string s = "tet";
    ReserveHuge(s, 4 * n);
    EXPECT_GE(s.capacity(), 4 * n);
    EXPECT_EQ(s, "tet");
  }
}

}  // namespace
}  // namespace tetrefine
