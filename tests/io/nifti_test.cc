// NIfTI reading and writing: real files, the RAS frame, byte order, versions, scaling, errors.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <ostream>
#include <random>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "client/io/nifti_reader.h"
#include "client/io/nifti_writer.h"
#include "client/io/read_volume.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "tests/io/io_test_util.h"
#include "tests/io/nifti_builder.h"
#include "tests/io/widening_cases.h"
#include "tests/support/child_process.h"

namespace tetrefine::io {
namespace {

using iotest::FloatSamples;
using iotest::Int16Samples;
using iotest::NiftiHeaderBytes;
using iotest::NiftiSpec;
using iotest::ScratchDir;
using iotest::SharedData;
using iotest::WriteBytes;
using ::testing::HasSubstr;
using ::testing::Not;

struct RealVolume {
  const char* file;
  Index3 dims;
  Vec3 voxel_mm;
  bool oblique;  // sform rotates or permutes axes
};

// In test names: GoogleTest would print the struct's bytes (a pointer among them, so the name
// changed from one build to the next), and ctest appends them.
void PrintTo(const RealVolume& v, std::ostream* os) { *os << v.file; }

// Grid and voxel size from ../shared/data/README.md.
class IoNiftiRealTest : public ::testing::TestWithParam<RealVolume> {};

TEST_P(IoNiftiRealTest, ReadsDimsAndVoxelSize) {
  const RealVolume& real = GetParam();
  absl::StatusOr<VolumeFile> file = ReadVolume(SharedData(real.file));
  ASSERT_TRUE(file.ok()) << file.status();
  const GridGeometry& grid = file->volume.grid();
  EXPECT_EQ(grid.dims, real.dims);
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(grid.spacing[a], real.voxel_mm[a], 1e-4) << "axis " << a;
  EXPECT_EQ(file->volume.type(), VoxelType::kInt16);
  // Oblique volumes carry their rotation in the direction now: no warning, and every sample sits
  // where the file's affine puts it.
  EXPECT_TRUE(file->warnings.empty());
  EXPECT_EQ(file->volume.axis_aligned(), !real.oblique);
  if (real.oblique) {
    for (const Index3& s : {Index3{0, 0, 0}, Index3{real.dims[0] - 1, 3, 1},
                            Index3{7, real.dims[1] - 1, real.dims[2] - 1}}) {
      Vec3 world;
      for (int r = 0; r < 3; ++r) {
        world[r] = file->affine[r][3];
        for (int c = 0; c < 3; ++c) world[r] += file->affine[r][c] * static_cast<double>(s[c]);
      }
      const Vec3 u = file->volume.ContinuousIndex(world);
      for (int a = 0; a < 3; ++a) EXPECT_NEAR(u[a], static_cast<double>(s[a]), 1e-9);
      EXPECT_NEAR(file->volume.Sample(world), file->volume.At(s[0], s[1], s[2]), 1e-6);
    }
  }
  const auto range = file->volume.ValueRange();
  EXPECT_LT(range[0], range[1]);
}

INSTANTIATE_TEST_SUITE_P(
    IoSharedData, IoNiftiRealTest,
    ::testing::Values(RealVolume{"anatomical_33x41x25.nii", {33, 41, 25}, {2, 2, 2}, false},
                      RealVolume{"epi_brain_58x58x24.nii.gz", {58, 58, 24}, {4, 4, 5}, true},
                      RealVolume{"t1_brain_128x128x62.nii.gz", {128, 128, 62}, {2, 2, 3}, true}));

// anatomical.nii is big-endian with sform x = -2 i + 32: reading must flip x so that the first
// sample is the most-left voxel.
TEST(IoNiftiRealTest, AnatomicalIsInRasMillimetres) {
  absl::StatusOr<VolumeFile> file = ReadNifti(SharedData("anatomical_33x41x25.nii"));
  ASSERT_TRUE(file.ok()) << file.status();
  const GridGeometry& grid = file->volume.grid();
  EXPECT_DOUBLE_EQ(grid.origin[0], 32.0 - 2.0 * 32);
  EXPECT_DOUBLE_EQ(grid.origin[1], -40.0);
  EXPECT_DOUBLE_EQ(grid.origin[2], -16.0);
  EXPECT_DOUBLE_EQ(file->affine[0][0], -2.0);
  EXPECT_DOUBLE_EQ(file->affine[0][3], 32.0);
}

// The frame pin: a file whose sform has a negative x scale. Sampling at the world position
// (RAS mm) of file voxel (i, j, k) must give that voxel's value.
void ExpectWorldSamplesMatchVoxels(const VolumeFile& file, const std::vector<float>& values,
                                   const std::array<int, 3>& n,
                                   const std::array<std::array<double, 4>, 3>& affine) {
  for (int k = 0; k < n[2]; ++k) {
    for (int j = 0; j < n[1]; ++j) {
      for (int i = 0; i < n[0]; ++i) {
        Vec3 world;
        for (int r = 0; r < 3; ++r) {
          world[r] = affine[r][0] * i + affine[r][1] * j + affine[r][2] * k + affine[r][3];
        }
        EXPECT_NEAR(file.volume.Sample(world), values[(k * n[1] + j) * n[0] + i], 1e-9)
            << "voxel (" << i << ", " << j << ", " << k << ") at world (" << world[0] << ", "
            << world[1] << ", " << world[2] << ")";
      }
    }
  }
}

std::vector<float> Ramp(int count) {
  std::vector<float> values(count);
  for (int i = 0; i < count; ++i) values[i] = static_cast<float>(i * 3 % 17) + 0.25f * i;
  return values;
}

TEST(IoNiftiFrameTest, NegativeXScaleSformIsWorldRas) {
  ScratchDir dir;
  const std::array<int, 3> n{4, 3, 5};
  const std::array<std::array<double, 4>, 3> sform{
      {{-2.0, 0, 0, 10.0}, {0, 3.0, 0, -20.0}, {0, 0, 1.5, 5.0}}};
  NiftiSpec spec;
  spec.dim = {3, n[0], n[1], n[2], 1, 1, 1, 1};
  spec.pixdim = {1, 2, 3, 1.5, 0, 0, 0, 0};
  spec.sform_code = 2;
  spec.srow = sform;
  const std::vector<float> values = Ramp(n[0] * n[1] * n[2]);
  const std::string path = dir.File("neg_x.nii");
  WriteBytes(path, NiftiHeaderBytes(spec) + FloatSamples(values, false));

  absl::StatusOr<VolumeFile> file = ReadVolume(path);
  ASSERT_TRUE(file.ok()) << file.status();
  EXPECT_TRUE(file->warnings.empty());
  const GridGeometry& grid = file->volume.grid();
  EXPECT_EQ(grid.spacing, (Vec3{2.0, 3.0, 1.5}));
  EXPECT_EQ(grid.origin, (Vec3{10.0 - 2.0 * 3, -20.0, 5.0}));
  ExpectWorldSamplesMatchVoxels(*file, values, n, sform);
  // Between voxels the trilinear value is the average of the neighbours, in world terms too.
  const double mid = file->volume.Sample({10.0 - 1.0, -20.0, 5.0});
  EXPECT_NEAR(mid, (values[0] + values[1]) / 2.0, 1e-9);
}

// Metres and micrometres are scaled to millimetres, as niftilib and ITK read them, and said:
// nibabel does not scale them (an outside review, 2026-11-29, found it silent).
TEST(IoNiftiFrameTest, MetresAndMicronsAreScaledAndSaid) {
  ScratchDir dir;
  const std::array<int, 3> n{2, 2, 2};
  for (const auto& [units, scale, word] :
       {std::tuple{1, 1000.0, "metres"}, {3, 0.001, "micrometres"}, {2, 1.0, ""}}) {
    NiftiSpec spec;
    spec.dim = {3, n[0], n[1], n[2], 1, 1, 1, 1};
    spec.pixdim = {1, 2, 3, 1.5, 0, 0, 0, 0};
    spec.sform_code = 2;
    spec.srow = {{{2.0, 0, 0, 1.0}, {0, 3.0, 0, 0}, {0, 0, 1.5, 0}}};
    spec.xyzt_units = units;
    const std::string path = dir.File(absl::StrCat("units_", units, ".nii"));
    WriteBytes(path, NiftiHeaderBytes(spec) + FloatSamples(Ramp(8), false));
    absl::StatusOr<VolumeFile> file = ReadVolume(path);
    ASSERT_TRUE(file.ok()) << file.status();
    EXPECT_EQ(file->volume.grid().spacing, (Vec3{2.0 * scale, 3.0 * scale, 1.5 * scale}));
    if (*word == '\0') {
      EXPECT_TRUE(file->warnings.empty());
    } else {
      ASSERT_EQ(file->warnings.size(), 1u);
      EXPECT_EQ(
          file->warnings[0],
          absl::StrCat(path, ": xyzt_units says ", word,
                       ": coordinates are scaled to millimetres (x", units == 1 ? "1000" : "0.001",
                       "), as niftilib and ITK read them; nibabel does not scale them"));
    }
  }
}

TEST(IoNiftiFrameTest, QformWithQfacIsWorldRas) {
  ScratchDir dir;
  const std::array<int, 3> n{3, 4, 2};
  // Quaternion (b, c, d) = (0, 1, 0) is a 180 degree turn about y: diag(-1, 1, -1); qfac = -1
  // negates the z column, giving diag(-1, 1, 1) * pixdim.
  NiftiSpec spec;
  spec.dim = {3, n[0], n[1], n[2], 1, 1, 1, 1};
  spec.pixdim = {-1, 2, 2.5, 4, 0, 0, 0, 0};
  spec.qform_code = 1;
  spec.quatern = {0, 1, 0};
  spec.qoffset = {7, -3, 11};
  const std::vector<float> values = Ramp(n[0] * n[1] * n[2]);
  const std::string path = dir.File("qform.nii.gz");
  // Written uncompressed under a .gz name: the reader decides by content, not name.
  WriteBytes(path, NiftiHeaderBytes(spec) + FloatSamples(values, false));
  absl::StatusOr<VolumeFile> file = ReadNifti(path);
  ASSERT_TRUE(file.ok()) << file.status();
  EXPECT_TRUE(file->warnings.empty());
  ExpectWorldSamplesMatchVoxels(*file, values, n,
                                {{{-2, 0, 0, 7}, {0, 2.5, 0, -3}, {0, 0, 4, 11}}});
}

// Without qform and sform the spacing is pixdim; a zero or NaN one is read as 1, and said (it
// was silent until a CLI sweep found it). Such a file is placed as the standard's method 1 says,
// which nibabel does not do: said too, with a good pixdim alone (a file-format sweep).
TEST(IoNiftiFrameTest, ZeroOrNanPixdimWithoutTransformsIsOneAndWarned) {
  ScratchDir dir;
  NiftiSpec spec;
  spec.pixdim = {1, 0, 2, std::numeric_limits<double>::quiet_NaN(), 0, 0, 0, 0};
  const std::string path = dir.File("pixdim.nii");
  WriteBytes(path, NiftiHeaderBytes(spec) + FloatSamples(Ramp(8), false));
  absl::StatusOr<VolumeFile> file = ReadNifti(path);
  ASSERT_TRUE(file.ok()) << file.status();
  EXPECT_EQ(file->volume.grid().spacing, (Vec3{1, 2, 1}));
  ASSERT_EQ(file->warnings.size(), 3u);
  const std::string method_one =
      path +
      ": no qform or sform (both codes 0): placed by pixdim alone, voxel (0, 0, 0) at the "
      "origin, as the NIfTI standard's method 1 says; nibabel centres such a volume and mirrors "
      "x, so meshes made in its coordinates will not line up";
  EXPECT_EQ(file->warnings[0], method_one);
  EXPECT_EQ(file->warnings[1],
            path +
                ": pixdim[1] is 0 and the file has no qform or sform: voxel size 1 used along "
                "axis 0");
  EXPECT_TRUE(absl::StrContains(file->warnings[2], "pixdim[3] is nan")) << file->warnings[2];
  spec.pixdim = {1, 3, 2, 1, 0, 0, 0, 0};
  WriteBytes(path, NiftiHeaderBytes(spec) + FloatSamples(Ramp(8), false));
  file = ReadNifti(path);
  ASSERT_TRUE(file.ok()) << file.status();
  EXPECT_EQ(file->warnings, std::vector<std::string>{method_one});
  EXPECT_EQ(file->volume.grid().origin, (Vec3{0, 0, 0}));
}

TEST(IoNiftiFrameTest, ObliqueSformBecomesTheDirection) {
  ScratchDir dir;
  const std::array<int, 3> n{3, 3, 3};
  NiftiSpec spec;
  spec.dim = {3, 3, 3, 3, 1, 1, 1, 1};
  spec.pixdim = {1, 2, 2, 2, 0, 0, 0, 0};
  spec.sform_code = 1;
  const double c = std::cos(0.3) * 2, s = std::sin(0.3) * 2;
  spec.srow = {{{c, -s, 0, 1}, {s, c, 0, 2}, {0, 0, 2, 3}}};
  const std::string path = dir.File("oblique.nii");
  const std::vector<float> values = Ramp(27);
  WriteBytes(path, NiftiHeaderBytes(spec) + FloatSamples(values, false));
  absl::StatusOr<VolumeFile> file = ReadNifti(path);
  ASSERT_TRUE(file.ok()) << file.status();
  EXPECT_TRUE(file->warnings.empty());
  EXPECT_NEAR(file->affine[1][0], s, 1e-6);
  const GridGeometry& grid = file->volume.grid();
  EXPECT_EQ(grid.origin, (Vec3{1, 2, 3}));
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(grid.spacing[a], 2.0, 1e-6);
  // Columns are the unit world directions of i, j, k; storage order is kept.
  const Mat3 expected{c / 2, -s / 2, 0, s / 2, c / 2, 0, 0, 0, 1};
  for (int i = 0; i < 9; ++i) EXPECT_NEAR(grid.direction[i], expected[i], 1e-6) << i;
  EXPECT_FLOAT_EQ(file->volume.At(1, 0, 0), values[1]);
  // The float32 sform rounds at 1e-7, so the world samples match to that.
  for (int k = 0; k < n[2]; ++k) {
    for (int j = 0; j < n[1]; ++j) {
      for (int i = 0; i < n[0]; ++i) {
        const Vec3 world{c * i - s * j + 1, s * i + c * j + 2, 2.0 * k + 3};
        EXPECT_NEAR(file->volume.Sample(world), values[(k * n[1] + j) * n[0] + i], 1e-4)
            << "voxel (" << i << ", " << j << ", " << k << ")";
      }
    }
  }
}

TEST(IoNiftiTest, BigEndianAndNifti2AndPairsReadTheSameVolume) {
  ScratchDir dir;
  const std::vector<float> values = Ramp(2 * 3 * 4);
  for (int version : {1, 2}) {
    for (bool big : {false, true}) {
      for (bool pair : {false, true}) {
        SCOPED_TRACE(::testing::Message()
                     << "version " << version << " big " << big << " pair " << pair);
        NiftiSpec spec;
        spec.version = version;
        spec.big_endian = big;
        spec.pair = pair;
        spec.dim = {3, 2, 3, 4, 1, 1, 1, 1};
        spec.sform_code = 1;
        spec.srow = {{{0.5, 0, 0, -1}, {0, 0.75, 0, 2}, {0, 0, 1.25, 3}}};
        std::string path;
        const std::string header = NiftiHeaderBytes(spec);
        const std::string samples = FloatSamples(values, big);
        if (pair) {
          path = dir.File("pair.hdr");
          WriteBytes(path, header);
          WriteBytes(dir.File("pair.img"), samples);
        } else {
          path = dir.File("single.nii");
          WriteBytes(path, header + samples);
        }
        absl::StatusOr<VolumeFile> file = ReadVolume(path);
        ASSERT_TRUE(file.ok()) << file.status();
        EXPECT_EQ(file->volume.grid().spacing, (Vec3{0.5, 0.75, 1.25}));
        EXPECT_EQ(file->volume.grid().origin, (Vec3{-1, 2, 3}));
        for (int k = 0; k < 4; ++k) {
          for (int j = 0; j < 3; ++j) {
            for (int i = 0; i < 2; ++i) {
              EXPECT_EQ(file->volume.At(i, j, k), values[(k * 3 + j) * 2 + i]);
            }
          }
        }
      }
    }
  }
}

// A .hdr/.img pair named by its .img half reads through its header, as nibabel reads it; with
// no header beside it, the message names the header it looked for.
TEST(IoNiftiTest, APairNamedByItsImgHalfReadsThroughItsHeader) {
  ScratchDir dir;
  NiftiSpec spec;
  spec.pair = true;
  spec.dim = {3, 2, 3, 4, 1, 1, 1, 1};
  std::vector<float> values(24);
  for (size_t i = 0; i < values.size(); ++i) values[i] = static_cast<float>(i) * 1.5f;
  WriteBytes(dir.File("pair.hdr"), NiftiHeaderBytes(spec));
  WriteBytes(dir.File("pair.img"), FloatSamples(values, false));
  absl::StatusOr<VolumeFile> by_header = ReadVolume(dir.File("pair.hdr"));
  absl::StatusOr<VolumeFile> by_image = ReadVolume(dir.File("pair.img"));
  ASSERT_TRUE(by_header.ok()) << by_header.status();
  ASSERT_TRUE(by_image.ok()) << by_image.status();
  EXPECT_EQ(by_image->volume.grid().dims, by_header->volume.grid().dims);
  for (int64_t i = 0; i < 24; ++i) {
    EXPECT_EQ(by_image->volume.At(i % 2, (i / 2) % 3, i / 6), values[i]);
  }
  WriteBytes(dir.File("lone.img"), FloatSamples(values, false));
  absl::StatusOr<VolumeFile> lone = ReadVolume(dir.File("lone.img"));
  ASSERT_FALSE(lone.ok());
  EXPECT_THAT(std::string(lone.status().message()),
              HasSubstr("an .img file holds only samples, and its header " + dir.File("lone.hdr") +
                        " is missing"));
}

TEST(IoNiftiTest, AppliesSlopeAndIntercept) {
  ScratchDir dir;
  NiftiSpec spec;
  spec.datatype = 4;  // int16
  spec.slope = 2.0;
  spec.inter = -1.5;
  const std::vector<int16_t> raw{-3, 0, 1, 2, 100, -100, 7, 8};
  const std::string path = dir.File("scaled.nii");
  WriteBytes(path, NiftiHeaderBytes(spec) + Int16Samples(raw, false));
  absl::StatusOr<VolumeFile> file = ReadNifti(path);
  ASSERT_TRUE(file.ok()) << file.status();
  EXPECT_EQ(file->volume.type(), VoxelType::kFloat32);
  EXPECT_EQ(file->volume.At(0, 0, 0), -7.5);
  EXPECT_EQ(file->volume.At(0, 0, 1), 198.5);

  spec.slope = 1.0;  // identity scaling keeps the stored type
  spec.inter = 0.0;
  WriteBytes(path, NiftiHeaderBytes(spec) + Int16Samples(raw, false));
  file = ReadNifti(path);
  ASSERT_TRUE(file.ok()) << file.status();
  EXPECT_EQ(file->volume.type(), VoxelType::kInt16);
  EXPECT_EQ(file->volume.At(0, 0, 1), 100);

  // A slope that is not a number is no scaling (niftilib's and nibabel's reading), intercept
  // and all, and the warning says so; a valid slope with a NaN intercept stays refused.
  spec.slope = std::numeric_limits<double>::quiet_NaN();
  spec.inter = 5.0;
  WriteBytes(path, NiftiHeaderBytes(spec) + Int16Samples(raw, false));
  file = ReadNifti(path);
  ASSERT_TRUE(file.ok()) << file.status();
  EXPECT_EQ(file->volume.type(), VoxelType::kInt16);
  EXPECT_EQ(file->volume.At(0, 0, 1), 100);
  // (The other warning: this file has no qform or sform.)
  ASSERT_EQ(file->warnings.size(), 2u);
  EXPECT_THAT(file->warnings[0], HasSubstr("scl_slope is nan, not a scaling"));
  spec.slope = 2.0;
  spec.inter = std::numeric_limits<double>::quiet_NaN();
  WriteBytes(path, NiftiHeaderBytes(spec) + Int16Samples(raw, false));
  EXPECT_THAT(std::string(ReadNifti(path).status().message()),
              HasSubstr("intensity scaling is not finite"));
}

int16_t NiftiDatatype(StoredType type) {
  switch (type) {
    case StoredType::kInt8:
      return 256;
    case StoredType::kUint32:
      return 768;
    case StoredType::kInt64:
      return 1024;
    case StoredType::kUint64:
      return 1280;
    default:
      ADD_FAILURE() << "not a widening type";
      return 0;
  }
}

// int8, uint32, int64 and uint64 (nibabel writes an int8 mask as int8 and keeps a uint32 label
// map's type) read as the Python client sends such arrays: every value as stored, or refused.
TEST(IoNiftiTest, WideIntegerTypesReadExactlyOrAreRefused) {
  ScratchDir dir;
  for (const iotest::WideningCase& c : iotest::WideningCases()) {
    for (int version : {1, 2}) {
      for (bool big_endian : {false, true}) {
        SCOPED_TRACE(::testing::Message() << "v" << version << (big_endian ? " big" : " little"));
        NiftiSpec spec;
        spec.version = version;
        spec.big_endian = big_endian;
        spec.datatype = NiftiDatatype(c.stored);
        const std::string path = dir.File("wide.nii");
        WriteBytes(path, NiftiHeaderBytes(spec) + iotest::WideningBytes(c, big_endian));
        iotest::ExpectWidened(c, ReadVolume(path), path);
      }
    }
  }
}

// Scaled, they are float32 from int8 (as from the other types of at most 16 bits) and float64
// from the 32- and 64-bit ones, whose values float32 would round. A scaled value is computed, not
// stored, so a 64-bit one beyond 2^53 is no refusal: it is rounded as every scaled value is.
TEST(IoNiftiTest, ScaledWideIntegerTypesAreFloat) {
  ScratchDir dir;
  const struct {
    std::string label;
    double slope, inter;
    VoxelType read_as;
  } scalings[] = {{"int8 extremes", 0.5, -3.0, VoxelType::kFloat32},
                  {"uint32 within int32", 0.25, 1.0, VoxelType::kFloat64},
                  {"uint32 beyond int32", 0.5, 10.0, VoxelType::kFloat64},
                  {"int64 at -2^53 and 2^53", 0.5, 0.0, VoxelType::kFloat64},
                  {"uint64 beyond 2^53", 2.0, 1.0, VoxelType::kFloat64}};
  const std::vector<iotest::WideningCase> cases = iotest::WideningCases();
  for (const auto& scaling : scalings) {
    const auto c = std::find_if(cases.begin(), cases.end(),
                                [&](const auto& w) { return w.label == scaling.label; });
    ASSERT_NE(c, cases.end()) << scaling.label;
    for (bool big_endian : {false, true}) {
      SCOPED_TRACE(::testing::Message() << scaling.label << (big_endian ? " big" : " little"));
      NiftiSpec spec;
      spec.big_endian = big_endian;
      spec.datatype = NiftiDatatype(c->stored);
      spec.slope = scaling.slope;
      spec.inter = scaling.inter;
      const std::string path = dir.File("scaled.nii");
      WriteBytes(path, NiftiHeaderBytes(spec) + iotest::WideningBytes(*c, big_endian));
      absl::StatusOr<VolumeFile> file = ReadVolume(path);
      ASSERT_TRUE(file.ok()) << file.status();
      EXPECT_EQ(file->volume.type(), scaling.read_as);
      for (int n = 0; n < 8; ++n) {
        // The stored value as the reader converts it (exactly, up to 2^53), then scaled.
        double x = 0;
        ASSERT_TRUE(absl::SimpleAtod(c->values[n], &x));
        double want = scaling.slope * x + scaling.inter;
        if (scaling.read_as == VoxelType::kFloat32) want = static_cast<float>(want);
        EXPECT_EQ(file->volume.At(n % 2, (n / 2) % 2, n / 4), want) << "sample " << n;
      }
    }
  }
}

// nibabel (python3-nibabel) writes int8, uint32 and int64 files, little- and big-endian, plain
// and with a scaling; what nibabel's own get_fdata reads from each is what ReadVolume must read.
constexpr char kNibabelScript[] = R"PY(
import sys, numpy as np, nibabel
out = sys.argv[1]
cases = {
    'int8': (np.int8, [-128, 127, 0, -1, 1, 64, -64, 5], 'int16', 'float32'),
    'uint32': (np.uint32, [4294967295, 0, 2147483648, 1, 5, 6, 7, 8], 'float64', 'float64'),
    'uint32_labels': (np.uint32, [0, 2147483647, 1, 65536, 7, 100000, 3, 2], 'int32', 'float64'),
    'int64': (np.int64, [-2**53, 2**53, 0, -1, 2**31, -2**31 - 1, 7, 8], 'float64', 'float64'),
}
for name, (dtype, values, plain_type, scaled_type) in cases.items():
    data = np.array(values, dtype=dtype).reshape((2, 2, 2), order='F')
    # The usual way: an image saved by nibabel (gzip, nibabel's own byte order).
    path = '%s/%s.nii.gz' % (out, name)
    nibabel.save(nibabel.Nifti1Image(data, np.eye(4), dtype=dtype), path)
    files = [(path, plain_type)]
    # A header nibabel builds, in both byte orders, with and without scl_slope / scl_inter.
    for endian in '<>':
        for scaled in (False, True):
            header = nibabel.Nifti1Header(endianness=endian)
            header.set_data_dtype(dtype)
            header.set_data_shape(data.shape)
            header.set_sform(np.eye(4), code=1)
            if scaled:
                header.set_slope_inter(0.5, -3.0)
            header['vox_offset'] = 352
            path = '%s/%s_%s%s.nii' % (out, name, 'big' if endian == '>' else 'little',
                                       '_scaled' if scaled else '')
            with open(path, 'wb') as f:
                header.write_to(f)
                f.seek(352)
                f.write(data.astype(np.dtype(dtype).newbyteorder(endian)).tobytes(order='F'))
            files.append((path, scaled_type if scaled else plain_type))
    for path, expected_type in files:
        image = nibabel.load(path)
        stored = image.get_data_dtype()
        assert stored.newbyteorder('<') == np.dtype(dtype).newbyteorder('<'), (path, stored)
        values = image.get_fdata()
        for k in range(2):
            for j in range(2):
                for i in range(2):
                    print(path, expected_type, i, j, k, repr(float(values[i, j, k])))
)PY";

TEST(IoNiftiTest, WideIntegerFilesNibabelWritesReadAsNibabelReadsThem) {
  if (!std::filesystem::exists(iotest::kPython) ||
      testing::RunProcess({iotest::kPython, "-c", "import nibabel, numpy"}).exit_code != 0) {
    GTEST_SKIP() << "python3-nibabel is not installed";
  }
  ScratchDir dir;
  WriteBytes(dir.File("write.py"), kNibabelScript);
  const testing::ProcessResult run =
      testing::RunProcess({iotest::kPython, dir.File("write.py"), dir.path()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  std::istringstream lines(run.out);
  std::string path, type, last;
  int i, j, k;
  double value;
  int files = 0, samples = 0;
  absl::StatusOr<VolumeFile> file = absl::UnknownError("no file yet");
  while (lines >> path >> type >> i >> j >> k >> value) {
    SCOPED_TRACE(path);
    if (path != last) {
      file = ReadVolume(path);
      ASSERT_TRUE(file.ok()) << file.status();
      EXPECT_EQ(VoxelTypeName(file->volume.type()), type);
      last = path;
      ++files;
    }
    EXPECT_EQ(file->volume.At(i, j, k), value) << i << " " << j << " " << k;
    ++samples;
  }
  EXPECT_EQ(files, 20);
  EXPECT_EQ(samples, 160);
}

TEST(IoNiftiTest, WriterRoundTripsEveryTypeAndVersion) {
  ScratchDir dir;
  std::mt19937_64 rng(7);
  for (VoxelType type : {VoxelType::kUint8, VoxelType::kInt16, VoxelType::kUint16,
                         VoxelType::kInt32, VoxelType::kFloat32, VoxelType::kFloat64}) {
    for (int version : {1, 2}) {
      for (const char* name : {"v.nii", "v.nii.gz"}) {
        SCOPED_TRACE(::testing::Message() << VoxelTypeName(type) << " v" << version << " " << name);
        GridGeometry grid;
        grid.dims = {5, 3, 4};
        // float-exact geometry for NIfTI-1, arbitrary doubles for NIfTI-2.
        grid.origin = version == 1 ? Vec3{-12.5, 3.25, 100} : Vec3{-12.1, 3.3, 0.1};
        grid.spacing = version == 1 ? Vec3{0.5, 2, 1.25} : Vec3{0.3, 2.7, 1.1};
        std::vector<std::byte> data(60 * VoxelSize(type));
        for (std::byte& b : data) b = static_cast<std::byte>(rng());
        if (type == VoxelType::kFloat32 || type == VoxelType::kFloat64) {
          // Random bytes could be NaN; write finite ramps instead.
          for (int i = 0; i < 60; ++i) {
            if (type == VoxelType::kFloat32) {
              const float f = 0.1f * i - 3;
              std::memcpy(data.data() + 4 * i, &f, 4);
            } else {
              const double d = 0.1 * i - 3;
              std::memcpy(data.data() + 8 * i, &d, 8);
            }
          }
        }
        absl::StatusOr<Volume> volume = Volume::CreateWhole(grid, type, data);
        ASSERT_TRUE(volume.ok()) << volume.status();
        const std::string path = dir.File(name);
        ASSERT_TRUE(WriteNifti(path, *volume, {.version = version}).ok());
        absl::StatusOr<VolumeFile> back = ReadVolume(path);
        ASSERT_TRUE(back.ok()) << back.status();
        EXPECT_TRUE(back->warnings.empty());
        EXPECT_EQ(back->volume.type(), type);
        EXPECT_EQ(back->volume.data(), data);
        EXPECT_EQ(back->volume.grid().dims, grid.dims);
        EXPECT_EQ(back->volume.grid().origin, grid.origin);
        EXPECT_EQ(back->volume.grid().spacing, grid.spacing);
      }
    }
  }
}

// An oblique volume written and read back keeps its frame, through the sform and through the
// qform alone (sform_code zeroed), for proper rotations and mirrored ones (qfac -1).
TEST(IoNiftiTest, WriterKeepsAnObliqueFrameInSformAndQform) {
  ScratchDir dir;
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (int trial = 0; trial < 8; ++trial) {
    double q[4] = {normal(rng), normal(rng), normal(rng), normal(rng)};
    const double len = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    for (double& x : q) x /= len;
    const double a = q[0], b = q[1], c = q[2], d = q[3];
    GridGeometry grid;
    grid.dims = {3, 4, 2};
    grid.origin = {-12.5, 40.25, 3.0};
    grid.spacing = {0.5, 1.25, 3.0};
    grid.direction = {a * a + b * b - c * c - d * d, 2 * (b * c - a * d),
                      2 * (b * d + a * c),           2 * (b * c + a * d),
                      a * a + c * c - b * b - d * d, 2 * (c * d - a * b),
                      2 * (b * d - a * c),           2 * (c * d + a * b),
                      a * a + d * d - b * b - c * c};
    if (trial % 2 == 1) {
      for (int row = 0; row < 3; ++row) grid.direction[3 * row + 1] *= -1.0;
    }
    std::vector<double> values(24);
    for (size_t i = 0; i < values.size(); ++i) values[i] = static_cast<double>(i * 5 % 11);
    absl::StatusOr<Volume> volume = Volume::FromDoubles(grid, values);
    ASSERT_TRUE(volume.ok()) << volume.status();
    for (int version : {1, 2}) {
      SCOPED_TRACE(::testing::Message() << "trial " << trial << " version " << version);
      const std::string path = dir.File(absl::StrCat("oblique", version, ".nii"));
      ASSERT_TRUE(WriteNifti(path, *volume, {.version = version}).ok());
      const double tolerance = version == 1 ? 2e-6 : 1e-8;
      for (bool sform : {true, false}) {
        SCOPED_TRACE(sform ? "sform" : "qform");
        if (!sform) {
          std::string bytes = iotest::ReadBytes(path);
          const size_t sform_code = version == 1 ? 254 : 348;
          bytes[sform_code] = 0;
          bytes[sform_code + 1] = 0;
          WriteBytes(path, bytes);
        }
        absl::StatusOr<VolumeFile> back = ReadVolume(path);
        ASSERT_TRUE(back.ok()) << back.status();
        EXPECT_TRUE(back->warnings.empty());
        const GridGeometry& g = back->volume.grid();
        for (int i = 0; i < 3; ++i) {
          EXPECT_NEAR(g.origin[i], grid.origin[i], 1e-5);
          EXPECT_NEAR(g.spacing[i], grid.spacing[i], 1e-6);
        }
        for (int i = 0; i < 9; ++i) EXPECT_NEAR(g.direction[i], grid.direction[i], tolerance) << i;
        EXPECT_EQ(back->volume.ValueRange(), volume->ValueRange());
      }
    }
  }
}

TEST(IoNiftiTest, WriterRejectsOtherExtensions) {
  ScratchDir dir;
  absl::StatusOr<Volume> volume =
      Volume::FromDoubles({{2, 2, 2}, {0, 0, 0}, {1, 1, 1}}, std::vector<double>(8, 1.0));
  ASSERT_TRUE(volume.ok());
  const absl::Status status = WriteNifti(dir.File("v.nrrd"), *volume);
  EXPECT_FALSE(status.ok());
  EXPECT_THAT(std::string(status.message()), HasSubstr("v.nrrd"));
}

TEST(IoNiftiErrorTest, TruncatedDataNamesPathAndSizes) {
  ScratchDir dir;
  NiftiSpec spec;
  spec.dim = {3, 10, 10, 10, 1, 1, 1, 1};
  const std::string path = dir.File("brain.nii");
  WriteBytes(path, NiftiHeaderBytes(spec) + std::string(1000, '\0'));
  const absl::Status status = ReadNifti(path).status();
  EXPECT_THAT(std::string(status.message()),
              HasSubstr("brain.nii: truncated: header says 4000 voxel bytes"));
  EXPECT_THAT(std::string(status.message()), HasSubstr("file has 1000"));
}

TEST(IoNiftiErrorTest, UnsupportedDatatypeAnd4DAreClearErrors) {
  ScratchDir dir;
  NiftiSpec spec;
  spec.datatype = 32;  // complex64 (int8, once refused here, is read: WideIntegerTypes...)
  const std::string path = dir.File("complex.nii");
  WriteBytes(path, NiftiHeaderBytes(spec) + std::string(64, '\0'));
  absl::Status status = ReadNifti(path).status();
  EXPECT_EQ(status.code(), absl::StatusCode::kUnimplemented);
  EXPECT_THAT(std::string(status.message()), HasSubstr("NIfTI datatype 32 (complex64)"));
  EXPECT_THAT(std::string(status.message()), HasSubstr(path));

  spec.datatype = 16;
  spec.dim = {4, 2, 2, 2, 3, 1, 1, 1};
  WriteBytes(path, NiftiHeaderBytes(spec) + std::string(96, '\0'));
  status = ReadNifti(path).status();
  EXPECT_THAT(std::string(status.message()), HasSubstr("dim[4] = 3"));
  // A series says how to take one of its frames.
  EXPECT_THAT(std::string(status.message()),
              HasSubstr("4D series of 3 frames; take one first, e.g. frame k with `fslroi IN OUT "
                        "k 1`"));
  // dim[5] holds the values per voxel (a vector image, as nibabel writes one): not a series.
  spec.dim = {5, 2, 2, 2, 1, 3, 1, 1};
  WriteBytes(path, NiftiHeaderBytes(spec) + std::string(96, '\0'));
  status = ReadNifti(path).status();
  EXPECT_THAT(std::string(status.message()),
              HasSubstr("dim[5] = 3: only 3D volumes of one value per voxel are read (this is 3 "
                        "values per voxel (dim[5]: a vector, tensor or displacement image)"));
  EXPECT_THAT(std::string(status.message()), Not(HasSubstr("series")));
}

// vox_offset errors give the value the header holds (they said "-1" for every bad one), and a
// fraction is refused rather than dropped.
TEST(IoNiftiErrorTest, VoxOffsetErrorsNameTheValueWritten) {
  ScratchDir dir;
  const std::string good = NiftiHeaderBytes(NiftiSpec{}) + std::string(32, '\0');
  const struct {
    float value;
    std::string says;
  } cases[] = {{-100.0f, "vox_offset = -100: must be a whole number of bytes, at least 348"},
               {347.0f, "vox_offset = 347: must be a whole number of bytes, at least 348"},
               {352.5f, "vox_offset = 352.5: must be a whole number of bytes"},
               {std::nanf(""), "vox_offset = nan: must be a whole number"},
               {1e30f, "vox_offset = 1e+30: beyond the data file's 384 bytes"}};
  for (const auto& c : cases) {
    std::string bytes = good;
    std::memcpy(bytes.data() + 108, &c.value, 4);
    const std::string path = dir.File("offset.nii");
    WriteBytes(path, bytes);
    const absl::Status status = ReadNifti(path).status();
    EXPECT_THAT(std::string(status.message()), HasSubstr(c.says)) << c.value;
    EXPECT_THAT(std::string(status.message()), HasSubstr(path));
  }
}

TEST(IoNiftiErrorTest, EveryTruncationAndGarbageFailsCleanly) {
  ScratchDir dir;
  NiftiSpec spec;
  const std::string bytes = NiftiHeaderBytes(spec) + FloatSamples(Ramp(8), false);
  const std::string path = dir.File("cut.nii");
  for (size_t size = 0; size < bytes.size(); ++size) {
    WriteBytes(path, bytes.substr(0, size));
    const absl::Status status = ReadNifti(path).status();
    EXPECT_FALSE(status.ok()) << "size " << size;
    EXPECT_THAT(std::string(status.message()), HasSubstr(path));
  }
  std::mt19937_64 rng(3);
  for (int trial = 0; trial < 200; ++trial) {
    std::string garbage = bytes;
    for (int flips = 0; flips < 8; ++flips) garbage[rng() % 352] = static_cast<char>(rng());
    WriteBytes(path, garbage);
    (void)ReadNifti(path);  // any result but a crash
  }
  WriteBytes(path, std::string("\x1f\x8b garbage that is not gzip"));
  EXPECT_FALSE(ReadNifti(path).ok());
  EXPECT_EQ(ReadNifti(dir.File("missing.nii")).status().code(), absl::StatusCode::kNotFound);
}

}  // namespace
}  // namespace tetrefine::io
