#include "tests/io/widening_cases.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace tetrefine::io::iotest {
namespace {

template <typename T>
void Append(std::string& out, T value, bool big_endian) {
  char raw[sizeof(T)];
  std::memcpy(raw, &value, sizeof(T));
  if (big_endian) std::reverse(raw, raw + sizeof(T));  // the tests run on little-endian hosts
  out.append(raw, sizeof(T));
}

bool IsSigned(StoredType type) { return type == StoredType::kInt8 || type == StoredType::kInt64; }

// The value as a double, which must hold it exactly (the readers' results are int16, int32 or
// float64).
double Exact(const std::string& text, bool is_signed) {
  if (is_signed) {
    int64_t v = 0;
    EXPECT_TRUE(absl::SimpleAtoi(text, &v)) << text;
    EXPECT_LE(v < 0 ? -static_cast<double>(v) : static_cast<double>(v), 0x1p53) << text;
    return static_cast<double>(v);
  }
  uint64_t v = 0;
  EXPECT_TRUE(absl::SimpleAtoi(text, &v)) << text;
  EXPECT_LE(v, uint64_t{1} << 53) << text;
  return static_cast<double>(v);
}

}  // namespace

std::vector<WideningCase> WideningCases() {
  const auto cast = [](std::initializer_list<const char*> values) {
    return std::vector<std::string>(values.begin(), values.end());
  };
  return {
      {"int8 extremes", StoredType::kInt8, cast({"-128", "127", "0", "-1", "1", "64", "-64", "5"}),
       VoxelType::kInt16, ""},
      {"uint32 within int32", StoredType::kUint32,
       cast({"0", "2147483647", "1", "65536", "7", "100000", "3", "2"}), VoxelType::kInt32, ""},
      {"uint32 beyond int32", StoredType::kUint32,
       cast({"4294967295", "0", "2147483648", "1", "5", "6", "7", "8"}), VoxelType::kFloat64, ""},
      {"int64 within int32", StoredType::kInt64,
       cast({"-2147483648", "2147483647", "0", "-1", "5", "6", "7", "8"}), VoxelType::kInt32, ""},
      {"int64 at -2^53 and 2^53", StoredType::kInt64,
       cast({"-9007199254740992", "9007199254740992", "0", "-1", "2147483648", "-2147483649", "7",
             "8"}),
       VoxelType::kFloat64, ""},
      {"uint64 at 2^53", StoredType::kUint64,
       cast({"9007199254740992", "0", "4294967296", "1", "2", "3", "4", "5"}), VoxelType::kFloat64,
       ""},
      {"uint64 beyond 2^53", StoredType::kUint64,
       cast({"1", "9007199254740993", "0", "2", "3", "4", "5", "6"}), std::nullopt,
       "9007199254740993"},
      {"int64 below -2^53", StoredType::kInt64,
       cast({"0", "1", "-9007199254740993", "2", "3", "4", "5", "6"}), std::nullopt,
       "9007199254740993"},
      {"int64 minimum", StoredType::kInt64,
       cast({"-9223372036854775808", "9223372036854775807", "0", "1", "2", "3", "4", "5"}),
       std::nullopt, "9223372036854775808"},
      {"uint64 maximum", StoredType::kUint64,
       cast({"0", "1", "2", "3", "4", "5", "6", "18446744073709551615"}), std::nullopt,
       "18446744073709551615"},
  };
}

std::string WideningBytes(const WideningCase& c, bool big_endian) {
  std::string out;
  for (const std::string& text : c.values) {
    int64_t s = 0;
    uint64_t u = 0;
    if (IsSigned(c.stored)) {
      EXPECT_TRUE(absl::SimpleAtoi(text, &s)) << text;
    } else {
      EXPECT_TRUE(absl::SimpleAtoi(text, &u)) << text;
    }
    switch (c.stored) {
      case StoredType::kInt8:
        Append(out, static_cast<int8_t>(s), big_endian);
        break;
      case StoredType::kUint32:
        Append(out, static_cast<uint32_t>(u), big_endian);
        break;
      case StoredType::kInt64:
        Append(out, s, big_endian);
        break;
      case StoredType::kUint64:
        Append(out, u, big_endian);
        break;
      default:
        ADD_FAILURE() << "not a widening type";
    }
  }
  return out;
}

std::string WideningText(const WideningCase& c, const std::string& separator) {
  return absl::StrJoin(c.values, separator);
}

void ExpectWidened(const WideningCase& c, const absl::StatusOr<VolumeFile>& file,
                   const std::string& path) {
  SCOPED_TRACE(c.label);
  if (!c.read_as.has_value()) {
    ASSERT_FALSE(file.ok()) << "read as " << VoxelTypeName(file->volume.type());
    EXPECT_EQ(file.status().code(), absl::StatusCode::kInvalidArgument) << file.status();
    const std::string message(file.status().message());
    EXPECT_THAT(message, ::testing::HasSubstr(path));
    EXPECT_THAT(message, ::testing::HasSubstr(absl::StrCat(
                             StoredTypeName(c.stored), " values up to ", c.magnitude,
                             " do not fit int32 and would round in float64; rescale them first")));
    return;
  }
  ASSERT_TRUE(file.ok()) << file.status();
  EXPECT_EQ(file->volume.type(), *c.read_as) << VoxelTypeName(file->volume.type());
  ASSERT_EQ(file->volume.grid().dims, (Index3{2, 2, 2}));
  for (int n = 0; n < 8; ++n) {
    const int i = n % 2, j = (n / 2) % 2, k = n / 4;
    Vec3 world;
    for (int r = 0; r < 3; ++r) {
      world[r] = file->affine[r][3] + file->affine[r][0] * i + file->affine[r][1] * j +
                 file->affine[r][2] * k;
    }
    const Vec3 u = file->volume.ContinuousIndex(world);
    const double got = file->volume.At(std::llround(u[0]), std::llround(u[1]), std::llround(u[2]));
    EXPECT_EQ(got, Exact(c.values[n], IsSigned(c.stored))) << "sample " << n;
  }
}

}  // namespace tetrefine::io::iotest
