#include "tests/cli/cli_test_util.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "client/io/mesh_io.h"
#include "client/io/nifti_writer.h"
#include "gtest/gtest.h"

namespace tetrefine::clitest {

std::string TetrefinePath() { return TETREFINE_CLI_PATH; }

ProcessResult RunTetrefine(const std::vector<std::string>& args, const std::string& cwd,
                           double timeout_seconds) {
  std::vector<std::string> argv = {TetrefinePath()};
  argv.insert(argv.end(), args.begin(), args.end());
  return RunProcess(argv, cwd, timeout_seconds);
}

int ClosedPort() {
  const int s = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address = {};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  address.sin_port = 0;
  bind(s, reinterpret_cast<sockaddr*>(&address), sizeof(address));
  socklen_t length = sizeof(address);
  getsockname(s, reinterpret_cast<sockaddr*>(&address), &length);
  const int port = ntohs(address.sin_port);
  close(s);
  return port;
}

Volume BumpVolume(const Index3& dims, const Vec3& origin, const Vec3& spacing) {
  const GridGeometry grid{dims, origin, spacing};
  Vec3 center;
  double radius = 0.0;
  for (int a = 0; a < 3; ++a) {
    center[a] = origin[a] + 0.5 * static_cast<double>(dims[a] - 1) * spacing[a];
    radius = std::max(radius, 0.3 * static_cast<double>(dims[a] - 1) * spacing[a]);
  }
  std::vector<double> values;
  values.reserve(static_cast<size_t>(dims[0] * dims[1] * dims[2]));
  for (int64_t k = 0; k < dims[2]; ++k) {
    for (int64_t j = 0; j < dims[1]; ++j) {
      for (int64_t i = 0; i < dims[0]; ++i) {
        const Vec3 p = {origin[0] + static_cast<double>(i) * spacing[0],
                        origin[1] + static_cast<double>(j) * spacing[1],
                        origin[2] + static_cast<double>(k) * spacing[2]};
        double r2 = 0.0;
        for (int a = 0; a < 3; ++a) r2 += (p[a] - center[a]) * (p[a] - center[a]);
        values.push_back(100.0 * std::exp(-r2 / (radius * radius)) + 0.5 * p[0]);
      }
    }
  }
  return *Volume::FromDoubles(grid, values);
}

void WriteVolume(const std::string& path, const Volume& volume) {
  const absl::Status status = io::WriteNifti(path, volume);
  ASSERT_TRUE(status.ok()) << status;
}

void WriteMeshFile(const std::string& path, const Mesh& mesh) {
  io::MeshFile file{.mesh = mesh, .tet_iteration = {}, .tet_quality = {}};
  const absl::Status status = io::WriteMesh(path, file);
  ASSERT_TRUE(status.ok()) << status;
}

bool FileExists(const std::string& path) {
  std::error_code ec;
  return std::filesystem::exists(path, ec);
}

}  // namespace tetrefine::clitest
