// A DICOM series as the volume of every command: pydicom writes a CT-like series of a smooth
// field (rotated, in Hounsfield units), and `info`, `mesh`, `refine` and `verify` read it from its
// directory or from one of its files, as a user holding a scanner's export would.

#include <filesystem>
#include <string>
#include <vector>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "gtest/gtest.h"
#include "tests/cli/cli_test_util.h"
#include "tests/io/io_test_util.h"

namespace tetrefine::clitest {
namespace {

using io::iotest::kPython;
using io::iotest::ScratchDir;

constexpr char kWriteSeries[] = R"PY(
import sys, numpy as np
from pydicom.dataset import FileDataset, FileMetaDataset
from pydicom.uid import ExplicitVRLittleEndian, generate_uid
out = sys.argv[1]
rows, cols, n = 14, 16, 10
a = 0.25
r, c = np.array([np.cos(a), np.sin(a), 0]), np.array([-np.sin(a), np.cos(a), 0])
series, study = generate_uid(), generate_uid()
j, i = np.mgrid[0:rows, 0:cols]
for k in range(n):
    hu = 400 * np.tanh((np.hypot(i - 8, j - 7) + 0.5 * (k - 5) - 4.0)) + 40 * np.sin(0.5 * k)
    meta = FileMetaDataset()
    meta.MediaStorageSOPClassUID = "1.2.840.10008.5.1.4.1.1.2"
    meta.MediaStorageSOPInstanceUID = sop = generate_uid()
    meta.TransferSyntaxUID = ExplicitVRLittleEndian
    name = "%s/slice%02d.dcm" % (out, (7 * k) % n)
    ds = FileDataset(name, {}, file_meta=meta, preamble=b"\0" * 128)
    ds.is_little_endian, ds.is_implicit_VR = True, False
    ds.SOPClassUID, ds.SOPInstanceUID = meta.MediaStorageSOPClassUID, sop
    ds.StudyInstanceUID, ds.SeriesInstanceUID = study, series
    ds.Modality = "CT"
    ds.ImagePositionPatient = ["%.6f" % x for x in np.array([30.0, -12.0, 5.0]) + 1.5 * k * np.cross(r, c)]
    ds.ImageOrientationPatient = ["%.8f" % x for x in list(r) + list(c)]
    ds.PixelSpacing = [1.0, 1.0]
    ds.Rows, ds.Columns = rows, cols
    ds.SamplesPerPixel, ds.PhotometricInterpretation = 1, "MONOCHROME2"
    ds.BitsAllocated, ds.BitsStored, ds.HighBit, ds.PixelRepresentation = 16, 12, 11, 1
    ds.RescaleIntercept, ds.RescaleSlope = -1024, 1
    ds.PixelData = np.round(hu + 1024).astype(np.int16).tobytes()
    ds.save_as(name, write_like_original=False)
)PY";

TEST(CliDicom, EveryCommandReadsASeries) {
  if (!std::filesystem::exists(kPython) ||
      RunProcess({kPython, "-c", "import pydicom, numpy"}).exit_code != 0) {
    GTEST_SKIP() << "python3-pydicom is not installed";
  }
  ScratchDir dir;
  const std::string series = dir.File("ct");
  std::filesystem::create_directories(series);
  const ProcessResult wrote = RunProcess({kPython, "-c", kWriteSeries, series});
  ASSERT_EQ(wrote.exit_code, 0) << wrote.err;

  const ProcessResult info = RunTetrefine({"info", series});
  ASSERT_EQ(info.exit_code, 0) << info.err;
  for (const char* text :
       {"16 x 14 x 10", "float32", "oblique", "value range        [-425, 440]"}) {
    EXPECT_TRUE(absl::StrContains(info.out, text)) << text << " missing from\n" << info.out;
  }
  const std::string mesh = dir.File("grid.vtu");
  const ProcessResult meshed =
      RunTetrefine({"mesh", "--volume", series, "--block", "3", "--output", mesh});
  ASSERT_EQ(meshed.exit_code, 0) << meshed.err;
  // One file of the series names the same volume as its directory.
  const std::string refined = dir.File("refined.vtu");
  const ProcessResult refine =
      RunTetrefine({"refine", "--volume", series + "/slice03.dcm", "--mesh", mesh, "--epsilon",
                    "0.05", "--threads", "1", "--output", refined});
  ASSERT_EQ(refine.exit_code, 0) << refine.err;
  EXPECT_TRUE(absl::StrContains(refine.out, "converged")) << refine.out;
  const ProcessResult verify =
      RunTetrefine({"verify", "--volume", series, "--mesh", refined, "--epsilon", "0.05"});
  EXPECT_EQ(verify.exit_code, 0) << verify.err << verify.out;
  EXPECT_TRUE(absl::StrContains(verify.out, "valid")) << verify.out;
  // A broken series: the message names the file and the attribute.
  std::filesystem::remove(series + "/slice05.dcm");
  const ProcessResult gap = RunTetrefine({"info", series});
  EXPECT_EQ(gap.exit_code, 2);
  EXPECT_TRUE(absl::StrContains(gap.err, "slice spacing is uneven")) << gap.err;
  EXPECT_TRUE(absl::StrContains(gap.err, series)) << gap.err;
}

}  // namespace
}  // namespace tetrefine::clitest
