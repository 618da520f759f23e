// FillLater (core/fill_later.h): arrays on either side of the huge-page threshold hold what is
// written to them through growth, copies and moves, large ones start on a 2 MiB boundary, and
// a size whose byte count overflows is refused rather than wrapped.
#include "core/fill_later.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <new>
#include <random>
#include <utility>

namespace tetrefine {
namespace {

using Alloc = DefaultInitAllocator<uint64_t>;
constexpr std::size_t kThresholdElements = Alloc::kHugeThreshold / sizeof(uint64_t);

uint64_t Pattern(uint64_t seed, std::size_t i) { return seed * 0x9E3779B97F4A7C15ull ^ i; }

void Fill(FillLater<uint64_t>& v, uint64_t seed) {
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = Pattern(seed, i);
}

// The first `n` elements hold the pattern; reports the first that does not.
::testing::AssertionResult Holds(const FillLater<uint64_t>& v, std::size_t n, uint64_t seed) {
  for (std::size_t i = 0; i < n; ++i) {
    if (v[i] != Pattern(seed, i)) return ::testing::AssertionFailure() << "element " << i;
  }
  return ::testing::AssertionSuccess();
}

TEST(FillLater, HoldsItsContentsOnBothSidesOfTheThreshold) {
  std::mt19937_64 rng(3);
  std::uniform_int_distribution<std::size_t> near(kThresholdElements - 1000,
                                                  kThresholdElements + 1000);
  for (int round = 0; round < 12; ++round) {
    const std::size_t n = round < 4 ? kThresholdElements - 1 + round : near(rng);
    const uint64_t seed = rng();
    FillLater<uint64_t> v(n);
    Fill(v, seed);
    if (n >= kThresholdElements) {
      EXPECT_EQ(reinterpret_cast<uintptr_t>(v.data()) % Alloc::kHugePage, 0u) << "n " << n;
    }
    EXPECT_TRUE(Holds(v, n, seed)) << "n " << n;
    // Growth across the threshold moves the contents between the two kinds of storage.
    v.resize(3 * n);
    EXPECT_TRUE(Holds(v, n, seed)) << "grown from n " << n;
    const FillLater<uint64_t> copy = v;
    EXPECT_TRUE(Holds(copy, n, seed)) << "copy, n " << n;
    FillLater<uint64_t> moved = std::move(v);
    EXPECT_TRUE(Holds(moved, n, seed)) << "moved, n " << n;
    moved.resize(n / 3);
    moved.shrink_to_fit();
    EXPECT_TRUE(Holds(moved, n / 3, seed)) << "shrunk, n " << n;
  }
}

TEST(FillLater, RefusesASizeWhoseBytesOverflow) {
  Alloc a;
  EXPECT_THROW(a.allocate(SIZE_MAX / sizeof(uint64_t)), std::bad_alloc);
}

}  // namespace
}  // namespace tetrefine
