#pragma once

// Helpers for the tests that run the real `tetrefine` binary: a process runner with a time
// limit, a tetrefine_server child on a free loopback port, and small generated inputs.

#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "core/mesh.h"
#include "core/volume.h"

namespace tetrefine::clitest {

struct ProcessResult {
  int exit_code = -1;  // 128 + signal when killed by a signal
  std::string out;
  std::string err;
  bool timed_out = false;
  double seconds = 0.0;
};

// Runs `argv` (argv[0] is the program path) in `cwd` (empty: ours) with stdin closed, collecting
// stdout and stderr. Killed with SIGKILL after `timeout_seconds`.
ProcessResult RunProcess(const std::vector<std::string>& argv, const std::string& cwd = "",
                         double timeout_seconds = 120.0);

// The tetrefine binary under test with `args`.
ProcessResult RunTetrefine(const std::vector<std::string>& args, const std::string& cwd = "",
                           double timeout_seconds = 120.0);

// Lines of `text` (a final newline does not start an empty line).
std::vector<std::string> Lines(const std::string& text);

// A tetrefine_server child listening on 127.0.0.1 at a port of its choosing (it logs the port).
// The destructor sends SIGTERM, waits up to 20 s, then SIGKILLs: it never outlives the test.
class ServerProcess {
 public:
  explicit ServerProcess(const std::vector<std::string>& extra_flags = {});
  ~ServerProcess();
  ServerProcess(const ServerProcess&) = delete;
  ServerProcess& operator=(const ServerProcess&) = delete;

  bool started() const { return port_ > 0; }
  std::string address() const { return "127.0.0.1:" + std::to_string(port_); }
  // What it logged while starting (for failure messages).
  std::string log() const;

 private:
  int pid_ = -1;
  int port_ = 0;
  int fd_ = -1;
  std::string startup_log_;
  std::thread drain_;  // keeps reading the log so the server never blocks on a full pipe
};

// A loopback port nothing listens on (bound, then closed).
int ClosedPort();

// A float64 volume of dims samples on [origin, origin + (dims - 1) spacing] whose values vary
// smoothly with a sharp-ish bump, so refinement has work for a few iterations.
Volume BumpVolume(const Index3& dims, const Vec3& origin, const Vec3& spacing);

// Writes `volume` as NIfTI at `path`; fails the test on error.
void WriteVolume(const std::string& path, const Volume& volume);
// Writes `mesh` (no per-tet arrays) at `path`; fails the test on error.
void WriteMeshFile(const std::string& path, const Mesh& mesh);

bool FileExists(const std::string& path);

}  // namespace tetrefine::clitest
