// Legacy VTK STRUCTURED_POINTS images as volumes: geometry, frames, types, attributes to skip,
// what VTK 9 writes (against VTK's own probe), and errors that say a mesh is not a volume.
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "client/io/mesh_io.h"
#include "client/io/read_volume.h"
#include "client/io/vtk_legacy_format.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "tests/io/io_test_util.h"
#include "tests/io/vtk_probe.h"
#include "tests/io/widening_cases.h"

namespace tetrefine::io::vtk_legacy_image_test {
namespace {

using iotest::kPython;
using iotest::ScratchDir;
using iotest::WriteBytes;
using ::testing::HasSubstr;

constexpr int kNx = 3, kNy = 4, kNz = 2;
double RampValue(int i, int j, int k) { return 7.0 * ((k * kNy + j) * kNx + i) - 20.0; }

std::string RampText() {
  std::vector<std::string> words;
  for (int k = 0; k < kNz; ++k) {
    for (int j = 0; j < kNy; ++j) {
      for (int i = 0; i < kNx; ++i) words.push_back(absl::StrCat(RampValue(i, j, k)));
    }
  }
  return absl::StrJoin(words, " ");
}

// An ASCII STRUCTURED_POINTS file as vtkStructuredPointsWriter lays it out; `before` goes between
// POINT_DATA and the samples (attributes to skip).
std::string AsciiImage(const std::string& title = "vtk output",
                       const std::string& geometry = "SPACING 2 3 4\nORIGIN 10 -20 30\n",
                       const std::string& before = "", const std::string& type = "short") {
  return absl::StrCat("# vtk DataFile Version 4.2\n", title, "\nASCII\nDATASET STRUCTURED_POINTS\n",
                      "DIMENSIONS ", kNx, " ", kNy, " ", kNz, "\n", geometry, "POINT_DATA ",
                      kNx * kNy * kNz, "\n", before, "SCALARS density ", type,
                      "\nLOOKUP_TABLE default\n", RampText(), "\n");
}

// Sample (i, j, k) at `origin` + (2i, 3j, 4k) with x and y negated when `lps`.
void ExpectRamp(const VolumeFile& file, const Vec3& origin, bool lps = false) {
  for (int k = 0; k < kNz; ++k) {
    for (int j = 0; j < kNy; ++j) {
      for (int i = 0; i < kNx; ++i) {
        Vec3 p{origin[0] + 2 * i, origin[1] + 3 * j, origin[2] + 4 * k};
        if (lps) p = {-p[0], -p[1], p[2]};
        EXPECT_EQ(file.volume.Sample(p), RampValue(i, j, k)) << i << " " << j << " " << k;
      }
    }
  }
}

TEST(IoVtkLegacyImageTest, StructuredPointsAreAVolume) {
  ScratchDir dir;
  const std::string path = dir.File("ramp.vtk");
  WriteBytes(path, AsciiImage());
  EXPECT_TRUE(IsVtkLegacyImage(path));
  absl::StatusOr<VolumeFile> file = ReadVolume(path);
  ASSERT_TRUE(file.ok()) << file.status();
  EXPECT_EQ(file->volume.type(), VoxelType::kInt16);
  EXPECT_EQ(file->volume.grid().dims, (Index3{kNx, kNy, kNz}));
  ExpectRamp(*file, {10, -20, 30});

  // A title tagged as Slicer tags its files: the coordinates are LPS.
  WriteBytes(path, AsciiImage("Slicer volume SPACE=LPS"));
  file = ReadVolume(path);
  ASSERT_TRUE(file.ok()) << file.status();
  ExpectRamp(*file, {10, -20, 30}, /*lps=*/true);

  // ASPECT_RATIO (SPACING's old name) and a DIRECTION that reverses x.
  WriteBytes(path, AsciiImage("vtk output",
                              "ASPECT_RATIO 2 3 4\nORIGIN 10 -20 30\nDIRECTION -1 0 0 0 1 "
                              "0 0 0 1\n"));
  file = ReadVolume(path);
  ASSERT_TRUE(file.ok()) << file.status();
  for (int i = 0; i < kNx; ++i)
    EXPECT_EQ(file->volume.Sample({10.0 - 2 * i, -20, 30}), RampValue(i, 0, 0));
}

TEST(IoVtkLegacyImageTest, OtherAttributesAreSkippedAndTypesKeptWhereExact) {
  ScratchDir dir;
  const std::string path = dir.File("attributes.vtk");
  std::string ones;
  for (int n = 0; n < 3 * kNx * kNy * kNz; ++n) ones += "1 ";
  WriteBytes(path, AsciiImage("vtk output", "SPACING 2 3 4\nORIGIN 10 -20 30\n",
                              absl::StrCat("VECTORS gradient float\n", ones, "\n")));
  absl::StatusOr<VolumeFile> file = ReadVolume(path);
  ASSERT_TRUE(file.ok()) << file.status();
  ExpectRamp(*file, {10, -20, 30});

  // ASCII values that do not fit the declared type are kept exactly, as float64.
  WriteBytes(path,
             AsciiImage("vtk output", "SPACING 2 3 4\nORIGIN 10 -20 30\n", "", "unsigned_char"));
  file = ReadVolume(path);
  ASSERT_TRUE(file.ok()) << file.status();
  EXPECT_EQ(file->volume.type(), VoxelType::kFloat64);  // -20 is no unsigned char
  ExpectRamp(*file, {10, -20, 30});
  WriteBytes(path, AsciiImage("vtk output", "SPACING 2 3 4\nORIGIN 10 -20 30\n", "", "float"));
  file = ReadVolume(path);
  ASSERT_TRUE(file.ok()) << file.status();
  EXPECT_EQ(file->volume.type(), VoxelType::kFloat32);
}

TEST(IoVtkLegacyImageTest, BinarySamplesAreBigEndian) {
  ScratchDir dir;
  const std::string path = dir.File("binary.vtk");
  std::string text = absl::StrCat(
      "# vtk DataFile Version 3.0\nvtk output\nBINARY\nDATASET STRUCTURED_POINTS\nDIMENSIONS ", kNx,
      " ", kNy, " ", kNz, "\nSPACING 2 3 4\nORIGIN 10 -20 30\nPOINT_DATA ", kNx * kNy * kNz,
      "\nSCALARS density unsigned_short 1\nLOOKUP_TABLE default\n");
  for (int n = 0; n < kNx * kNy * kNz; ++n) {
    const int v = 7 * n + 1000;  // RampValue + 1020
    text.push_back(static_cast<char>(v >> 8));
    text.push_back(static_cast<char>(v & 255));
  }
  text += "\n";
  WriteBytes(path, text);
  absl::StatusOr<VolumeFile> file = ReadVolume(path);
  ASSERT_TRUE(file.ok()) << file.status();
  EXPECT_EQ(file->volume.type(), VoxelType::kUint16);
  EXPECT_EQ(file->volume.Sample({12, -17, 34}), RampValue(1, 1, 1) + 1020);
}

TEST(IoVtkLegacyImageTest, AMeshIsNotAVolumeAndAVolumeIsNotAMesh) {
  ScratchDir dir;
  const std::string image = dir.File("image.vtk");
  WriteBytes(image, AsciiImage());
  absl::StatusOr<MeshFile> mesh = ReadMesh(image);
  ASSERT_FALSE(mesh.ok());
  EXPECT_THAT(
      std::string(mesh.status().message()),
      HasSubstr("DATASET STRUCTURED_POINTS is a volume (an image), not a tetrahedral mesh"));

  const std::string grid = dir.File("grid.vtk");
  WriteBytes(grid,
             "# vtk DataFile Version 4.2\nmesh\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 0 double\n"
             "CELLS 0 0\nCELL_TYPES 0\n");
  EXPECT_FALSE(IsVtkLegacyImage(grid));
  absl::StatusOr<VolumeFile> volume = ReadVolume(grid);
  ASSERT_FALSE(volume.ok());
  EXPECT_THAT(std::string(volume.status().message()),
              HasSubstr("only STRUCTURED_POINTS holds a volume (this is a mesh: --mesh)"));
}

TEST(IoVtkLegacyImageTest, ErrorsNameTheFileAndLine) {
  ScratchDir dir;
  const std::string path = dir.File("bad.vtk");
  const std::string good = AsciiImage();
  const struct {
    std::string text;
    std::string says;
  } cases[] = {
      {absl::StrCat("# vtk DataFile Version 4.2\nt\nASCII\nDATASET STRUCTURED_POINTS\n",
                    "DIMENSIONS 3 4 1\nSPACING 1 1 1\nORIGIN 0 0 0\nPOINT_DATA 12\n",
                    "SCALARS s float\nLOOKUP_TABLE default\n0 1 2 3 4 5 6 7 8 9 10 11\n"),
       "DIMENSIONS gives 1 samples along z"},
      {AsciiImage("t", "SPACING 2 3 4\nORIGIN 10 nan 30\n"), "ORIGIN"},
      {AsciiImage("t", "SPACING 2 0 4\nORIGIN 10 -20 30\n"), "axis"},
      {std::string(good).replace(good.find("POINT_DATA 24"), 13, "POINT_DATA 25"),
       "POINT_DATA 25 does not match the 24 points"},
      {good.substr(0, good.find("SCALARS")), "no POINT_DATA SCALARS"},
      {std::string(good).replace(good.find("SCALARS density short"), 21, "SCALARS density short 3"),
       "declares 72 density"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.says);
    WriteBytes(path, c.text);
    absl::StatusOr<VolumeFile> file = ReadVolume(path);
    ASSERT_FALSE(file.ok());
    EXPECT_THAT(std::string(file.status().message()), HasSubstr(path));
    EXPECT_THAT(std::string(file.status().message()), HasSubstr(c.says));
  }
  for (size_t size = 0; size < good.size(); size += 4) {
    WriteBytes(path, good.substr(0, size));
    const absl::StatusOr<VolumeFile> file = ReadVolume(path);
    if (!file.ok()) {
      EXPECT_THAT(std::string(file.status().message()), HasSubstr(path));
    }
  }
}

// A 2 x 2 x 2 image of a widening case's values, ASCII or BINARY (big-endian, as VTK writes).
std::string WideImage(const std::string& type, const iotest::WideningCase& c, bool binary) {
  return absl::StrCat("# vtk DataFile Version 3.0\nwide\n", binary ? "BINARY" : "ASCII",
                      "\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 2 2\nSPACING 1 1 1\n",
                      "ORIGIN 0 0 0\nPOINT_DATA 8\nSCALARS v ", type, "\nLOOKUP_TABLE default\n",
                      binary ? iotest::WideningBytes(c, true) : iotest::WideningText(c), "\n");
}

// char, unsigned_int, 64-bit integers: read as the Python client sends such arrays, binary
// values exactly as stored (a binary int64 beyond 2^53 was rounded without a word) and ASCII
// ones by the same rule (int32 where they fit, float64 to 2^53, refused beyond).
TEST(IoVtkLegacyImageTest, WideIntegerTypesReadExactlyOrAreRefused) {
  ScratchDir dir;
  const std::string path = dir.File("wide.vtk");
  const auto names = [](StoredType type) -> std::vector<std::string> {
    switch (type) {
      case StoredType::kInt8:
        return {"char", "signed_char", "vtktypeint8"};
      case StoredType::kUint32:
        return {"unsigned_int", "vtktypeuint32"};
      case StoredType::kInt64:
        return {"long", "vtktypeint64"};
      case StoredType::kUint64:
        return {"unsigned_long", "vtktypeuint64"};
      default:
        ADD_FAILURE() << "not a widening type";
        return {};
    }
  };
  for (const iotest::WideningCase& c : iotest::WideningCases()) {
    for (const std::string& type : names(c.stored)) {
      for (bool binary : {true, false}) {
        SCOPED_TRACE(absl::StrCat(type, binary ? " binary" : " ascii"));
        WriteBytes(path, WideImage(type, c, binary));
        iotest::ExpectWidened(c, ReadVolume(path), path);
      }
    }
  }
}

// VTK 9 writes an image in both encodings and file versions and in several types; VTK's probe of
// a float64 copy gives the reference values.
constexpr char kVtkScript[] = R"PY(
import sys, vtk, numpy as np
from vtk.util import numpy_support as ns
out = sys.argv[1]
rng = np.random.default_rng(17)
base = rng.normal(90.0, 30.0, (6, 5, 7))
for n, (typ, binary, version) in enumerate([(np.int16, True, 42), (np.int16, False, 42),
        (np.float32, True, 51), (np.float64, False, 51), (np.uint8, True, 51),
        (np.int32, False, 42), (np.uint16, True, 42), (np.uint8, False, 42), (np.int8, True, 42),
        (np.uint32, False, 51), (np.int64, True, 51), (np.uint64, False, 42)]):
    values = np.clip(base, 0, 250).astype(typ)
    im = vtk.vtkImageData(); im.SetDimensions(7, 5, 6); im.SetSpacing(0.8, 1.25, 2.0)
    im.SetOrigin(-7.5, 3.0, 40.0)
    a = ns.numpy_to_vtk(values.ravel(), deep=1); a.SetName('ct'); im.GetPointData().SetScalars(a)
    name = '%s/image%d_%s_%s_%d.vtk' % (out, n, np.dtype(typ).name, 'binary' if binary else 'ascii', version)
    w = vtk.vtkStructuredPointsWriter(); w.SetInputData(im); w.SetFileName(name)
    w.SetFileVersion(version)
    w.SetFileTypeToBinary() if binary else w.SetFileTypeToASCII()
    assert w.Write() == 1
    exact = vtk.vtkImageData(); exact.DeepCopy(im)
    e = ns.numpy_to_vtk(values.astype(np.float64).ravel(), deep=1); e.SetName('ct')
    exact.GetPointData().SetScalars(e)
    points = vtk.vtkPoints()
    for _ in range(30):
        points.InsertNextPoint([rng.uniform(lo + 0.01, hi - 0.01) for lo, hi in
                                zip(im.GetBounds()[0::2], im.GetBounds()[1::2])])
    poly = vtk.vtkPolyData(); poly.SetPoints(points)
    probe = vtk.vtkProbeFilter(); probe.SetInputData(poly); probe.SetSourceData(exact); probe.Update()
    got = probe.GetOutput().GetPointData().GetArray('ct')
    for i in range(points.GetNumberOfPoints()):
        print(name, *points.GetPoint(i), repr(got.GetValue(i)))
)PY";

TEST(IoVtkLegacyImageTest, WhatVtkWritesSamplesAsVtkProbes) {
  if (!iotest::HaveVtkPython()) {
    GTEST_SKIP() << "python3-vtk9 is not installed (scripts/install-deps.sh installs it)";
  }
  ScratchDir dir;
  const int files = iotest::ExpectVolumesSampleAsVtkProbes(
      kVtkScript, dir, [](const std::string& name, const VolumeFile& file) {
        EXPECT_EQ(file.volume.grid().dims, (Index3{7, 5, 6})) << name;
      });
  EXPECT_EQ(files, 12);
}

}  // namespace
}  // namespace tetrefine::io::vtk_legacy_image_test
