// VTK XML images (.vti): geometry as vtkImageData defines it, pieces, every storage VTK 9 writes
// (compared with VTK's own trilinear probe), and errors that name the file and the array.
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "client/io/read_volume.h"
#include "client/io/vti_reader.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "tests/io/io_test_util.h"
#include "tests/io/vtk_probe.h"
#include "tests/io/widening_cases.h"

namespace tetrefine::io::vti_test {
namespace {

using iotest::kPython;
using iotest::ScratchDir;
using iotest::WriteBytes;
using ::testing::HasSubstr;

// Extent x 1..3, y -1..2, z 0..1 (3 x 4 x 2 samples), value of sample (i, j, k) counted from the
// extent's start: 7 n - 20 with n its index in x-fastest order.
constexpr int kNx = 3, kNy = 4, kNz = 2;
double RampValue(int i, int j, int k) { return 7.0 * ((k * kNy + j) * kNx + i) - 20.0; }

std::string RampText(int z0, int z1) {
  std::vector<std::string> words;
  for (int k = z0; k <= z1; ++k) {
    for (int j = 0; j < kNy; ++j) {
      for (int i = 0; i < kNx; ++i) words.push_back(absl::StrCat(RampValue(i, j, k)));
    }
  }
  return absl::StrJoin(words, " ");
}

// An ascii .vti as vtkXMLImageDataWriter lays it out, one piece per z range in `pieces`.
std::string AsciiVti(const std::string& image_attributes,
                     const std::vector<std::pair<int, int>>& pieces = {{0, 1}},
                     const std::string& point_data = "") {
  std::string out = absl::StrCat(
      "<?xml version=\"1.0\"?>\n<VTKFile type=\"ImageData\" version=\"1.0\" "
      "byte_order=\"LittleEndian\" header_type=\"UInt64\">\n  <ImageData ",
      image_attributes, ">\n");
  for (const auto& [z0, z1] : pieces) {
    absl::StrAppend(&out, "    <Piece Extent=\"1 3 -1 2 ", z0, " ", z1, "\">\n",
                    "      <PointData Scalars=\"density\">\n", point_data,
                    "        <DataArray type=\"Int16\" Name=\"density\" format=\"ascii\">\n",
                    "          ", RampText(z0, z1), "\n        </DataArray>\n",
                    "      </PointData>\n      <CellData>\n      </CellData>\n    </Piece>\n");
  }
  absl::StrAppend(&out, "  </ImageData>\n</VTKFile>\n");
  return out;
}

// `text` with the first `from` replaced by `to` (which must be there).
std::string Replaced(std::string text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

constexpr char kGeometry[] = "WholeExtent=\"1 3 -1 2 0 1\" Origin=\"10 -20 30\" Spacing=\"2 3 4\"";

// Sample (i, j, k) of the extent (counted from its start) lies at Origin + Spacing * (extent's
// first index + (i, j, k)): here (10 + 2 (1 + i), -20 + 3 (-1 + j), 30 + 4 k).
void ExpectRampAtVtkPoints(const VolumeFile& file) {
  for (int k = 0; k < kNz; ++k) {
    for (int j = 0; j < kNy; ++j) {
      for (int i = 0; i < kNx; ++i) {
        const Vec3 p{10.0 + 2 * (1 + i), -20.0 + 3 * (j - 1), 30.0 + 4 * k};
        EXPECT_EQ(file.volume.Sample(p), RampValue(i, j, k)) << i << " " << j << " " << k;
      }
    }
  }
}

TEST(IoVtiTest, SamplesSitWhereVtkImageDataPlacesThem) {
  ScratchDir dir;
  const std::string path = dir.File("ramp.vti");
  WriteBytes(path, AsciiVti(kGeometry));
  absl::StatusOr<VolumeFile> file = ReadVolume(path);
  ASSERT_TRUE(file.ok()) << file.status();
  EXPECT_EQ(file->volume.grid().dims, (Index3{kNx, kNy, kNz}));
  EXPECT_EQ(file->volume.grid().spacing, (Vec3{2, 3, 4}));
  EXPECT_EQ(file->volume.grid().origin, (Vec3{12, -23, 30}));
  EXPECT_TRUE(file->volume.axis_aligned());
  ExpectRampAtVtkPoints(*file);
}

TEST(IoVtiTest, NegativeSpacingAndDirectionFlipsAreExact) {
  // Direction diag(-1, 1, 1) with spacing 2 along x, and spacing -3 along y: each sample is still
  // at Origin + Direction (Spacing * index), the grid flipped to positive spacing.
  ScratchDir dir;
  const std::string path = dir.File("flipped.vti");
  WriteBytes(path, AsciiVti("WholeExtent=\"1 3 -1 2 0 1\" Origin=\"10 -20 30\" "
                            "Spacing=\"2 -3 4\" Direction=\"-1 0 0 0 1 0 0 0 1\""));
  absl::StatusOr<VolumeFile> file = ReadVolume(path);
  ASSERT_TRUE(file.ok()) << file.status();
  EXPECT_TRUE(file->volume.axis_aligned());
  for (int k = 0; k < kNz; ++k) {
    for (int j = 0; j < kNy; ++j) {
      for (int i = 0; i < kNx; ++i) {
        const Vec3 p{10.0 - 2 * (1 + i), -20.0 - 3 * (j - 1), 30.0 + 4 * k};
        EXPECT_EQ(file->volume.Sample(p), RampValue(i, j, k)) << i << " " << j << " " << k;
      }
    }
  }
}

TEST(IoVtiTest, PiecesThatTileTheExtentAreAssembled) {
  ScratchDir dir;
  const std::string path = dir.File("pieces.vti");
  WriteBytes(path, AsciiVti(kGeometry, {{0, 0}, {1, 1}}));
  absl::StatusOr<VolumeFile> file = ReadVolume(path);
  ASSERT_TRUE(file.ok()) << file.status();
  ExpectRampAtVtkPoints(*file);

  // Overlapping pieces (VTK's share a layer of points) read the same.
  WriteBytes(path, AsciiVti(kGeometry, {{0, 1}, {1, 1}}));
  file = ReadVolume(path);
  ASSERT_TRUE(file.ok()) << file.status();
  ExpectRampAtVtkPoints(*file);

  WriteBytes(path, AsciiVti(kGeometry, {{1, 1}}));
  EXPECT_THAT(std::string(ReadVolume(path).status().message()),
              HasSubstr("the pieces hold 12 samples, fewer than the 24 of WholeExtent"));
  // Two pieces holding the same layer: enough samples, not all of them.
  WriteBytes(path, AsciiVti(kGeometry, {{1, 1}, {1, 1}}));
  EXPECT_THAT(std::string(ReadVolume(path).status().message()),
              HasSubstr("the pieces cover 12 of the 24 samples"));
  // A WholeExtent of 2^60 samples and a small piece: an error, before any allocation.
  WriteBytes(path, Replaced(AsciiVti(kGeometry, {{0, 0}, {1, 1}}), "WholeExtent=\"1 3 -1 2 0 1\"",
                            "WholeExtent=\"1 1048576 -1 1048574 0 1048575\""));
  EXPECT_THAT(std::string(ReadVolume(path).status().message()),
              HasSubstr("the pieces hold 24 samples, fewer than the 1152921504606846976"));
}

TEST(IoVtiTest, ErrorsNameTheFileAndWhatIsWrong) {
  ScratchDir dir;
  const std::string path = dir.File("bad.vti");
  const struct {
    std::string text;
    std::string says;
  } cases[] = {
      {AsciiVti("WholeExtent=\"1 3 -1 2 0\" Origin=\"10 -20 30\" Spacing=\"2 3 4\""),
       "ImageData WholeExtent needs 6 integers"},
      {AsciiVti("WholeExtent=\"1 3 -1 2 0 0\" Origin=\"10 -20 30\" Spacing=\"2 3 4\""),
       "WholeExtent gives 1 samples along z"},
      {AsciiVti("WholeExtent=\"1 3 -1 2 0 1\" Origin=\"10 -20\" Spacing=\"2 3 4\""),
       "ImageData Origin has 2 numbers, expected 3"},
      {AsciiVti("WholeExtent=\"1 3 -1 2 0 1\" Origin=\"10 -20 30\" Spacing=\"2 nan 4\""),
       "Spacing: \"nan\" is not a finite number"},
      {AsciiVti("WholeExtent=\"1 3 -1 2 0 1\" Origin=\"10 -20 30\" Spacing=\"2 0 4\""), "axis"},
      {AsciiVti(std::string(kGeometry) + " Direction=\"1 0 0 0 1 0\""),
       "Direction has 6 numbers, expected 9"},
      {AsciiVti(kGeometry, {{0, 2}}), "Piece Extent is empty or outside WholeExtent"},
      {Replaced(AsciiVti(kGeometry), "type=\"ImageData\"", "type=\"RectilinearGrid\""),
       "VTKFile type \"RectilinearGrid\" is not ImageData"},
      {Replaced(AsciiVti(kGeometry), "type=\"Int16\"", "type=\"String\""),
       "DataArray \"density\" has type \"String\", expected a numeric type"},
      {Replaced(AsciiVti(kGeometry), "-20 -13", "-20 x"), "value 1 is not a valid number"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.says);
    WriteBytes(path, c.text);
    absl::StatusOr<VolumeFile> file = ReadVolume(path);
    ASSERT_FALSE(file.ok());
    EXPECT_THAT(std::string(file.status().message()), HasSubstr(path));
    EXPECT_THAT(std::string(file.status().message()), HasSubstr(c.says));
  }
}

TEST(IoVtiTest, WhichArrayIsTheVolumeIsSaid) {
  ScratchDir dir;
  const std::string path = dir.File("arrays.vti");
  std::string text = AsciiVti(kGeometry);
  // A vector array named as the active scalars.
  const std::string vectors =
      "        <DataArray type=\"Float32\" Name=\"gradient\" NumberOfComponents=\"3\" "
      "format=\"ascii\">0 0 0</DataArray>\n";
  WriteBytes(path, Replaced(AsciiVti(kGeometry, {{0, 1}}, vectors), "Scalars=\"density\"",
                            "Scalars=\"gradient\""));
  EXPECT_THAT(std::string(ReadVolume(path).status().message()),
              HasSubstr("PointData \"gradient\" has 3 components"));
  // Without Scalars, the first one-component array is the volume.
  WriteBytes(path, Replaced(AsciiVti(kGeometry, {{0, 1}}, vectors), "Scalars=\"density\"", ""));
  absl::StatusOr<VolumeFile> first = ReadVolume(path);
  ASSERT_TRUE(first.ok()) << first.status();
  ExpectRampAtVtkPoints(*first);

  WriteBytes(path, Replaced(text, "Scalars=\"density\"", "Scalars=\"mask\""));
  EXPECT_THAT(std::string(ReadVolume(path).status().message()),
              HasSubstr("PointData names Scalars \"mask\" but holds no such array"));

  std::string cells = text;
  const size_t from = cells.find("      <PointData");
  const size_t to = cells.find("      <CellData>");
  cells.replace(from, to - from, "");
  cells.replace(cells.find("      <CellData>\n      </CellData>"),
                std::string("      <CellData>\n      </CellData>").size(),
                "      <CellData><DataArray type=\"Int16\" Name=\"labels\" format=\"ascii\">1 2 3 "
                "4 5 6</DataArray></CellData>");
  WriteBytes(path, cells);
  EXPECT_THAT(std::string(ReadVolume(path).status().message()),
              HasSubstr("only cell data (CellData \"labels\")"));
}

TEST(IoVtiTest, TruncatedFilesAreErrorsNotCrashes) {
  ScratchDir dir;
  const std::string path = dir.File("cut.vti");
  const std::string good = AsciiVti(kGeometry, {{0, 0}, {1, 1}});
  for (size_t size = 0; size < good.size(); size += 5) {
    WriteBytes(path, good.substr(0, size));
    const absl::StatusOr<VolumeFile> file = ReadVolume(path);
    if (!file.ok()) {
      EXPECT_THAT(std::string(file.status().message()), HasSubstr(path));
    }
  }
}

// A 2 x 2 x 2 image whose point array of `type` is stored appended and raw, one block per piece
// (each piece a z layer of `pieces` bytes blocks, or one piece holding everything).
std::string AppendedVti(const std::string& type, const std::vector<std::string>& blocks,
                        bool big_endian) {
  std::string out = absl::StrCat(
      "<?xml version=\"1.0\"?>\n<VTKFile type=\"ImageData\" version=\"1.0\" byte_order=\"",
      big_endian ? "BigEndian" : "LittleEndian",
      "\" header_type=\"UInt64\">\n  <ImageData WholeExtent=\"0 1 0 1 0 1\" Origin=\"0 0 0\" "
      "Spacing=\"1 1 1\">\n");
  std::string appended;
  for (size_t p = 0; p < blocks.size(); ++p) {
    const std::string z = blocks.size() == 1 ? "0 1" : absl::StrCat(p, " ", p);
    absl::StrAppend(&out, "    <Piece Extent=\"0 1 0 1 ", z,
                    "\">\n      <PointData Scalars=\"v\">\n", "        <DataArray type=\"", type,
                    "\" Name=\"v\" format=\"appended\" offset=\"", appended.size(),
                    "\"/>\n      </PointData>\n    </Piece>\n");
    const uint64_t size = blocks[p].size();
    for (int b = 0; b < 8; ++b) {
      appended.push_back(static_cast<char>(size >> (big_endian ? 8 * (7 - b) : 8 * b)));
    }
    appended += blocks[p];
  }
  absl::StrAppend(&out, "  </ImageData>\n  <AppendedData encoding=\"raw\">\n   _", appended,
                  "\n  </AppendedData>\n</VTKFile>\n");
  return out;
}

std::string VtkTypeName(StoredType type) {
  switch (type) {
    case StoredType::kInt8:
      return "Int8";
    case StoredType::kUint32:
      return "UInt32";
    case StoredType::kInt64:
      return "Int64";
    case StoredType::kUint64:
      return "UInt64";
    default:
      ADD_FAILURE() << "not a widening type";
      return "";
  }
}

// Int8, UInt32, Int64 and UInt64 read as the Python client sends such arrays (UInt32 was float64
// whatever its values, and a value beyond 2^53 an error naming neither it nor its size). Whether
// the values fit int32 is decided over the whole image, not piece by piece.
TEST(IoVtiTest, WideIntegerTypesReadExactlyOrAreRefused) {
  ScratchDir dir;
  const std::string path = dir.File("wide.vti");
  for (const iotest::WideningCase& c : iotest::WideningCases()) {
    for (bool big_endian : {false, true}) {
      const std::string bytes = iotest::WideningBytes(c, big_endian);
      for (bool two_pieces : {false, true}) {
        SCOPED_TRACE(absl::StrCat(big_endian ? "big" : "little", two_pieces ? " two pieces" : ""));
        const std::vector<std::string> blocks =
            two_pieces ? std::vector<std::string>{bytes.substr(0, bytes.size() / 2),
                                                  bytes.substr(bytes.size() / 2)}
                       : std::vector<std::string>{bytes};
        WriteBytes(path, AppendedVti(VtkTypeName(c.stored), blocks, big_endian));
        iotest::ExpectWidened(c, ReadVolume(path), path);
      }
    }
  }
}

// Text Int64 samples widen as binary ones do: read through doubles, -2^53 - 1 became -2^53 and
// the image was taken where the same samples stored in binary are refused (an outside review,
// 2026-11-28).
TEST(IoVtiTest, AsciiInt64SamplesWidenAsBinaryOnes) {
  ScratchDir dir;
  const std::string path = dir.File("ascii.vti");
  int cases = 0;
  for (const iotest::WideningCase& c : iotest::WideningCases()) {
    if (c.stored != StoredType::kInt64) continue;
    SCOPED_TRACE(c.label);
    ++cases;
    WriteBytes(path,
               absl::StrCat("<?xml version=\"1.0\"?>\n<VTKFile type=\"ImageData\" "
                            "version=\"1.0\">\n<ImageData WholeExtent=\"0 1 0 1 0 1\" "
                            "Origin=\"0 0 0\" Spacing=\"1 1 1\">\n<Piece Extent=\"0 1 0 1 "
                            "0 1\">\n<PointData Scalars=\"v\">\n<DataArray type=\"Int64\" "
                            "Name=\"v\" format=\"ascii\">",
                            iotest::WideningText(c),
                            "</DataArray>\n</PointData>\n</Piece>\n</ImageData>\n</VTKFile>\n"));
    iotest::ExpectWidened(c, ReadVolume(path), path);
  }
  EXPECT_GE(cases, 2);
}

// VTK 9 (python3-vtk9) writes one image in every storage and type; VTK's own probe (trilinear
// inside each voxel) gives the reference values at points inside the image.
constexpr char kVtkScript[] = R"PY(
import sys, vtk, numpy as np
from vtk.util import numpy_support as ns
out = sys.argv[1]
rng = np.random.default_rng(11)
dims = (7, 5, 6)
base = rng.normal(100.0, 40.0, dims[::-1])
types = {'Int8': vtk.VTK_SIGNED_CHAR, 'UInt8': vtk.VTK_UNSIGNED_CHAR, 'Int16': vtk.VTK_SHORT,
         'UInt16': vtk.VTK_UNSIGNED_SHORT, 'Int32': vtk.VTK_INT, 'UInt32': vtk.VTK_UNSIGNED_INT,
         'Int64': vtk.VTK_LONG_LONG, 'UInt64': vtk.VTK_UNSIGNED_LONG_LONG, 'Float32': vtk.VTK_FLOAT,
         'Float64': vtk.VTK_DOUBLE}
np_types = {'Int8': np.int8, 'UInt8': np.uint8, 'Int16': np.int16, 'UInt16': np.uint16,
            'Int32': np.int32, 'UInt32': np.uint32, 'Int64': np.int64, 'UInt64': np.uint64,
            'Float32': np.float32, 'Float64': np.float64}
def image(type_name, oblique):
    values = {'Int8': np.clip(base, 0, 120), 'UInt64': np.clip(base, 0, None)}.get(type_name, base)
    im = vtk.vtkImageData()
    im.SetExtent(2, 2 + dims[0] - 1, -3, -3 + dims[1] - 1, 1, dims[2])
    im.SetSpacing(1.5, 2.0, 0.75)
    im.SetOrigin(-4.0, 6.0, 12.5)
    if oblique:
        c, s = np.cos(0.4), np.sin(0.4)
        im.SetDirectionMatrix(c, 0, s, 0, 1, 0, -s, 0, c)
    a = ns.numpy_to_vtk(values.astype(np_types[type_name]).ravel(), deep=1,
                        array_type=types[type_name])
    a.SetName('intensity')
    im.GetPointData().SetScalars(a)
    # VTK's probe answers in the source array's type: probe a float64 copy of the same values.
    probe_source = vtk.vtkImageData(); probe_source.DeepCopy(im)
    exact = ns.numpy_to_vtk(values.astype(np_types[type_name]).astype(np.float64).ravel(), deep=1)
    exact.SetName('intensity')
    probe_source.GetPointData().SetScalars(exact)
    g = vtk.vtkDoubleArray(); g.SetName('gradient'); g.SetNumberOfComponents(3)
    g.SetNumberOfTuples(im.GetNumberOfPoints()); g.Fill(1.0)
    im.GetPointData().AddArray(g)
    return im, probe_source
variants = []
for type_name in types:
    variants.append((type_name, 'appended', 'zlib', 64, 'little', False))
for mode in ['ascii', 'binary', 'appended']:
    for comp in [None, 'zlib', 'lz4', 'lzma']:
        if mode == 'ascii' and comp: continue
        for header in [32, 64]:
            variants.append(('Float32', mode, comp, header, 'little', False))
variants.append(('Int16', 'appended', None, 32, 'big', False))
variants.append(('Int16', 'binary', 'zlib', 64, 'big', False))
variants.append(('Float64', 'appended', 'zlib', 64, 'little', True))
variants.append(('Int16', 'binary', None, 32, 'little', True))
for n, (type_name, mode, comp, header, order, oblique) in enumerate(variants):
    im, probe_source = image(type_name, oblique)
    name = '%s/v%02d_%s_%s_%s_%d_%s%s.vti' % (out, n, type_name, mode, comp, header, order,
                                             '_oblique' if oblique else '')
    w = vtk.vtkXMLImageDataWriter(); w.SetInputData(im); w.SetFileName(name)
    {'ascii': w.SetDataModeToAscii, 'binary': w.SetDataModeToBinary,
     'appended': w.SetDataModeToAppended}[mode]()
    if mode == 'appended': w.EncodeAppendedDataOff()
    {None: w.SetCompressorTypeToNone, 'zlib': w.SetCompressorTypeToZLib,
     'lz4': w.SetCompressorTypeToLZ4, 'lzma': w.SetCompressorTypeToLZMA}[comp]()
    w.SetHeaderTypeToUInt32() if header == 32 else w.SetHeaderTypeToUInt64()
    w.SetByteOrderToBigEndian() if order == 'big' else w.SetByteOrderToLittleEndian()
    assert w.Write() == 1
    points = vtk.vtkPoints()
    for _ in range(40):
        ijk = [rng.uniform(e0 + 0.05, e1 - 0.05) for e0, e1 in
               zip(im.GetExtent()[0::2], im.GetExtent()[1::2])]
        p = [0.0, 0.0, 0.0]
        im.TransformContinuousIndexToPhysicalPoint(ijk, p)
        points.InsertNextPoint(p)
    poly = vtk.vtkPolyData(); poly.SetPoints(points)
    probe = vtk.vtkProbeFilter(); probe.SetInputData(poly); probe.SetSourceData(probe_source); probe.Update()
    values = probe.GetOutput().GetPointData().GetArray('intensity')
    mask = probe.GetOutput().GetPointData().GetArray('vtkValidPointMask')
    for i in range(points.GetNumberOfPoints()):
        if mask.GetValue(i):
            print(name, *points.GetPoint(i), repr(values.GetValue(i)))
)PY";

TEST(IoVtiTest, EveryStorageVtkWritesSamplesAsVtkProbes) {
  if (!iotest::HaveVtkPython()) {
    GTEST_SKIP() << "python3-vtk9 is not installed (scripts/install-deps.sh installs it)";
  }
  ScratchDir dir;
  const int files = iotest::ExpectVolumesSampleAsVtkProbes(
      kVtkScript, dir, [](const std::string& name, const VolumeFile& file) {
        EXPECT_EQ(file.volume.grid().dims, (Index3{7, 5, 6})) << name;
        EXPECT_EQ(file.volume.axis_aligned(), name.find("oblique") == std::string::npos) << name;
      });
  EXPECT_EQ(files, 32);
}

// VTK's parallel image writer: a .pvti index and one .vti per piece, for several piece counts,
// types and an oblique Direction; each read must sample as VTK's probe of the whole image.
constexpr char kPvtiScript[] = R"PY(
import sys, vtk, numpy as np
from vtk.util import numpy_support as ns
out = sys.argv[1]
rng = np.random.default_rng(29)
for n, (pieces, typ, oblique) in enumerate([(2, np.int16, False), (3, np.float32, True),
                                            (4, np.uint8, False)]):
    dims = (9, 7, 8)
    values = np.clip(rng.normal(80.0, 30.0, dims[::-1]), 0, 250).astype(typ)
    im = vtk.vtkImageData(); im.SetExtent(-2, 6, 1, 7, 0, 7)
    im.SetSpacing(1.25, 0.5, 2.0); im.SetOrigin(3.0, -4.0, 10.0)
    if oblique:
        c, s = np.cos(0.5), np.sin(0.5)
        im.SetDirectionMatrix(1, 0, 0, 0, c, -s, 0, s, c)
    a = ns.numpy_to_vtk(values.ravel(), deep=1); a.SetName('density')
    im.GetPointData().SetScalars(a)
    name = '%s/image%d.pvti' % (out, n)
    w = vtk.vtkXMLPImageDataWriter(); w.SetInputData(im); w.SetFileName(name)
    w.SetNumberOfPieces(pieces); w.SetStartPiece(0); w.SetEndPiece(pieces - 1)
    assert w.Write() == 1
    exact = vtk.vtkImageData(); exact.DeepCopy(im)
    e = ns.numpy_to_vtk(values.astype(np.float64).ravel(), deep=1); e.SetName('density')
    exact.GetPointData().SetScalars(e)
    points = vtk.vtkPoints()
    for _ in range(40):
        ijk = [rng.uniform(lo + 0.05, hi - 0.05) for lo, hi in
               zip(im.GetExtent()[0::2], im.GetExtent()[1::2])]
        p = [0.0, 0.0, 0.0]
        im.TransformContinuousIndexToPhysicalPoint(ijk, p)
        points.InsertNextPoint(p)
    poly = vtk.vtkPolyData(); poly.SetPoints(points)
    probe = vtk.vtkProbeFilter(); probe.SetInputData(poly); probe.SetSourceData(exact)
    probe.Update()
    got = probe.GetOutput().GetPointData().GetArray('density')
    for i in range(points.GetNumberOfPoints()):
        print(name, *points.GetPoint(i), repr(got.GetValue(i)))
)PY";

TEST(IoVtiTest, ParallelImagesSampleAsVtkProbes) {
  if (!iotest::HaveVtkPython()) {
    GTEST_SKIP() << "python3-vtk9 is not installed (scripts/install-deps.sh installs it)";
  }
  ScratchDir dir;
  const int files = iotest::ExpectVolumesSampleAsVtkProbes(
      kPvtiScript, dir, [](const std::string& name, const VolumeFile& file) {
        EXPECT_EQ(file.volume.grid().dims, (Index3{9, 7, 8})) << name;
      });
  EXPECT_EQ(files, 3);
}

TEST(IoVtiTest, ParallelImageErrorsNameTheIndexOrThePiece) {
  ScratchDir dir;
  const std::string index = dir.File("p.pvti");
  const auto pvti = [](const std::string& pieces) {
    return absl::StrCat(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"PImageData\" version=\"1.0\">\n"
        "<PImageData WholeExtent=\"1 3 -1 2 0 1\" GhostLevel=\"0\" Origin=\"10 -20 30\" "
        "Spacing=\"2 3 4\">\n<PPointData Scalars=\"density\"><PDataArray type=\"Int16\" "
        "Name=\"density\"/></PPointData>\n",
        pieces, "</PImageData>\n</VTKFile>\n");
  };
  // Two pieces, each a .vti of its own z layer: the whole ramp.
  WriteBytes(dir.File("p_0.vti"),
             Replaced(AsciiVti(kGeometry, {{0, 0}}), "0 1\" Origin", "0 0\" Origin"));
  WriteBytes(dir.File("p_1.vti"),
             Replaced(AsciiVti(kGeometry, {{1, 1}}), "0 1\" Origin", "1 1\" Origin"));
  WriteBytes(index, pvti("<Piece Extent=\"1 3 -1 2 0 0\" Source=\"p_0.vti\"/>\n"
                         "<Piece Extent=\"1 3 -1 2 1 1\" Source=\"p_1.vti\"/>\n"));
  absl::StatusOr<VolumeFile> file = ReadVolume(index);
  ASSERT_TRUE(file.ok()) << file.status();
  ExpectRampAtVtkPoints(*file);

  WriteBytes(index, pvti("<Piece Extent=\"1 3 -1 2 0 0\" Source=\"p_0.vti\"/>\n"));
  EXPECT_THAT(std::string(ReadVolume(index).status().message()),
              HasSubstr("the pieces hold 12 samples, fewer than the 24 of WholeExtent"));
  // Pieces that disagree on a Direction the index leaves out (VTK 9.1 writes it only there).
  WriteBytes(dir.File("d_0.vti"),
             AsciiVti(std::string(kGeometry) + " Direction=\"0 1 0 -1 0 0 0 0 1\"", {{0, 0}}));
  WriteBytes(dir.File("d_1.vti"),
             AsciiVti(std::string(kGeometry) + " Direction=\"1 0 0 0 1 0 0 0 1\"", {{1, 1}}));
  WriteBytes(index, pvti("<Piece Extent=\"1 3 -1 2 0 0\" Source=\"d_0.vti\"/>\n"
                         "<Piece Extent=\"1 3 -1 2 1 1\" Source=\"d_1.vti\"/>\n"));
  EXPECT_THAT(std::string(ReadVolume(index).status().message()),
              HasSubstr(absl::StrCat(dir.File("d_1.vti"),
                                     ":3: Direction differs from the earlier pieces'")));
  WriteBytes(index, pvti("<Piece Extent=\"1 3 -1 2 0 0\" Source=\"gone.vti\"/>\n"));
  EXPECT_THAT(std::string(ReadVolume(index).status().message()),
              HasSubstr(absl::StrCat(index, ": piece 0: ")));
  WriteBytes(index, pvti("<Piece Extent=\"1 3 -1 2 0 0\"/>\n"));
  EXPECT_THAT(std::string(ReadVolume(index).status().message()),
              HasSubstr("Piece has no Source file"));
  // A piece whose extent lies outside the index's grid is that piece's error.
  WriteBytes(dir.File("p_far.vti"),
             Replaced(Replaced(AsciiVti(kGeometry, {{0, 0}}), "0 1\" Origin", "0 0\" Origin"),
                      "<Piece Extent=\"1 3 -1 2 0 0\"", "<Piece Extent=\"1 3 -1 2 5 5\""));
  WriteBytes(index, pvti("<Piece Extent=\"1 3 -1 2 5 5\" Source=\"p_far.vti\"/>\n"));
  EXPECT_THAT(
      std::string(ReadVolume(index).status().message()),
      HasSubstr(absl::StrCat(dir.File("p_far.vti"), ":4: Piece Extent is empty or outside")));
}

}  // namespace
}  // namespace tetrefine::io::vti_test
