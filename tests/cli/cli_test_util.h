#pragma once

// Helpers for the tests that run the real `tetrefine` binary and small generated inputs. Processes
// (the CLI, a tetrefine_server on a free loopback port) are started by tests/support.

#include <string>
#include <vector>

#include "core/mesh.h"
#include "core/volume.h"
#include "tests/support/child_process.h"
#include "tests/support/server_process.h"

namespace tetrefine::clitest {

using testing::ProcessResult;
using testing::RunProcess;
using testing::ServerProcess;
using testing::SplitLines;

// The path of the tetrefine binary under test.
std::string TetrefinePath();

// The tetrefine binary under test with `args`.
ProcessResult RunTetrefine(const std::vector<std::string>& args, const std::string& cwd = "",
                           double timeout_seconds = 120.0);

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
