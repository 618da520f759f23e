#include "tests/io/vtk_probe.h"

#include <cmath>
#include <filesystem>
#include <sstream>

#include "client/io/read_volume.h"
#include "gtest/gtest.h"
#include "tests/support/child_process.h"

namespace tetrefine::io::iotest {

bool HaveVtkPython() {
  return std::filesystem::exists(kPython) &&
         testing::RunProcess({kPython, "-c", "import vtk, numpy"}).exit_code == 0;
}

int ExpectVolumesSampleAsVtkProbes(
    const std::string& script, const ScratchDir& dir,
    const std::function<void(const std::string& path, const VolumeFile& file)>& check) {
  WriteBytes(dir.File("write.py"), script);
  const testing::ProcessResult run =
      testing::RunProcess({kPython, dir.File("write.py"), dir.path()});
  EXPECT_EQ(run.exit_code, 0) << run.err;
  std::istringstream lines(run.out);
  std::string name, last;
  Vec3 p;
  double expected;
  int files = 0;
  absl::StatusOr<VolumeFile> file = absl::UnknownError("no file yet");
  while (lines >> name >> p[0] >> p[1] >> p[2] >> expected) {
    if (name != last) {
      file = ReadVolume(name);
      EXPECT_TRUE(file.ok()) << file.status();
      if (!file.ok()) return files;
      check(name, *file);
      last = name;
      ++files;
    }
    EXPECT_NEAR(file->volume.Sample(p), expected, 1e-9 * (1.0 + std::abs(expected)))
        << name << " at " << p[0] << " " << p[1] << " " << p[2];
  }
  return files;
}

}  // namespace tetrefine::io::iotest
