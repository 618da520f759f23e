// Regression tests for bugs the hardening work found, at the level of the library that had them
// (fuzzing inputs also sit in fuzz/corpus/<target>/regress-*; the process-level symptoms are in
// hardening_fault_test).

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "client/io/nifti_reader.h"
#include "client/io/nifti_writer.h"
#include "client/io/vtu_format.h"
#include "core/refine.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace tetrefine::hardening {
namespace {

using ::testing::HasSubstr;

class ScratchFile {
 public:
  explicit ScratchFile(const std::string& name)
      : path_((std::filesystem::temp_directory_path() /
               ("tetrefine-hardening-" + std::to_string(getpid()) + "-" + name))
                  .string()) {}
  ~ScratchFile() { std::filesystem::remove(path_); }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

std::string ReadAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

void WriteAll(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

// NIfTI-1 stores vox_offset as a float; converting 1e30 (or NaN, or a negative value) to an
// integer was undefined behaviour. It must be refused by name.
TEST(HardeningRegressionTest, NiftiVoxOffsetBeyondInt64IsRefused) {
  const GridGeometry grid{.dims = {2, 2, 2}, .origin = {0, 0, 0}, .spacing = {1, 1, 1}};
  const Volume volume = *Volume::FromDoubles(grid, {1, 2, 3, 4, 5, 6, 7, 8});
  ScratchFile file("vox_offset.nii");
  ASSERT_TRUE(io::WriteNifti(file.path(), volume).ok());
  const std::string good = ReadAll(file.path());
  for (float offset : {1e30f, -352.0f, std::numeric_limits<float>::quiet_NaN(),
                       std::numeric_limits<float>::infinity()}) {
    std::string bytes = good;
    std::memcpy(bytes.data() + 108, &offset, sizeof(offset));
    WriteAll(file.path(), bytes);
    const absl::StatusOr<io::VolumeFile> read = io::ReadNifti(file.path());
    ASSERT_FALSE(read.ok()) << "vox_offset " << offset;
    EXPECT_THAT(std::string(read.status().message()), HasSubstr("vox_offset")) << offset;
  }
}

// A .vtu cell offset or type beyond int64 was converted to an integer regardless (undefined
// behaviour). Such a file must be refused, or the cell ignored, by name.
TEST(HardeningRegressionTest, VtuOffsetsAndTypesBeyondInt64AreHandled) {
  auto vtu = [](const std::string& offsets, const std::string& types) {
    return R"(<VTKFile type="UnstructuredGrid" version="0.1"><UnstructuredGrid>
<Piece NumberOfPoints="5" NumberOfCells="3"><Points>
<DataArray type="Float64" NumberOfComponents="3" format="ascii">
0 0 0 1 0 0 0 1 0 0 0 1 1 1 1</DataArray></Points><Cells>
<DataArray type="Int32" Name="connectivity" format="ascii">0 1 2 3 0 1 2 1 2 3 4</DataArray>
<DataArray type="Float64" Name="offsets" format="ascii">)" +
           offsets + R"(</DataArray>
<DataArray type="Float64" Name="types" format="ascii">)" +
           types + R"(</DataArray>
</Cells></Piece></UnstructuredGrid></VTKFile>)";
  };
  for (const char* offset : {"1e300", "-1e300", "7555555555555555555555555555", "nan"}) {
    const absl::StatusOr<io::MeshFile> file =
        io::ParseVtu(vtu(std::string("4 ") + offset + " 11", "10 5 10"), "bad.vtu");
    ASSERT_FALSE(file.ok()) << offset;
    EXPECT_THAT(std::string(file.status().message()), HasSubstr("offsets")) << offset;
  }
  const absl::StatusOr<io::MeshFile> file = io::ParseVtu(vtu("4 7 11", "10 1e300 10"), "big.vtu");
  ASSERT_FALSE(file.ok());
  EXPECT_THAT(std::string(file.status().message()), HasSubstr("types"));
}

// The final lattice check ignored should_cancel: at order 64 over every tet (lattice_max_tets 0)
// a cancelled server call kept a core busy for minutes. It must stop within a poll interval.
TEST(HardeningRegressionTest, CancellationReachesTheLatticeCheck) {
  const int cells = 12;
  const GridGeometry grid{
      .dims = {cells + 1, cells + 1, cells + 1}, .origin = {0, 0, 0}, .spacing = {1, 1, 1}};
  std::vector<double> values;
  for (int k = 0; k <= cells; ++k) {
    for (int j = 0; j <= cells; ++j) {
      for (int i = 0; i <= cells; ++i) values.push_back(std::sin(0.4 * i) * std::cos(0.3 * j) + k);
    }
  }
  const Volume volume = *Volume::FromDoubles(grid, values);
  // Six tets a cell around the main diagonal (Kuhn): 10368 tets, conforming.
  Mesh mesh;
  auto vertex = [&](int i, int j, int k) {
    return static_cast<uint32_t>(i + (cells + 1) * (j + (cells + 1) * k));
  };
  for (int k = 0; k <= cells; ++k) {
    for (int j = 0; j <= cells; ++j) {
      for (int i = 0; i <= cells; ++i) mesh.points.push_back({1.0 * i, 1.0 * j, 1.0 * k});
    }
  }
  const int paths[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (int k = 0; k < cells; ++k) {
    for (int j = 0; j < cells; ++j) {
      for (int i = 0; i < cells; ++i) {
        for (const auto& path : paths) {
          int c[3] = {i, j, k};
          Tet tet;
          tet[0] = vertex(c[0], c[1], c[2]);
          for (int step = 0; step < 3; ++step) {
            ++c[path[step]];
            tet[step + 1] = vertex(c[0], c[1], c[2]);
          }
          if (SignedVolume6(mesh.points[tet[0]], mesh.points[tet[1]], mesh.points[tet[2]],
                            mesh.points[tet[3]]) < 0) {
            std::swap(tet[2], tet[3]);
          }
          mesh.tets.push_back(tet);
        }
      }
    }
  }
  RefineOptions options;
  options.max_iterations = 0;  // all the work is the lattice: 10368 tets x 47905 points
  options.lattice_n = 64;
  options.lattice_max_tets = 0;
  const auto start = std::chrono::steady_clock::now();
  options.should_cancel = [&] {
    return std::chrono::steady_clock::now() - start > std::chrono::milliseconds(300);
  };
  const absl::StatusOr<RefineResult> result = Refine(volume, mesh, options);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ASSERT_TRUE(result.ok()) << result.status();
  EXPECT_EQ(result->stop_reason, StopReason::kCancelled);
  // Uncancelled this takes about 20 s; a poll every few thousand samples stops it at once.
  EXPECT_LT(seconds, 3.0);
}

}  // namespace
}  // namespace tetrefine::hardening
