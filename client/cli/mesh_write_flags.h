#pragma once

// The flags that choose how a mesh file is encoded, shared by every command that writes a mesh
// (refine, mesh), so they are spelled, documented and checked in one place.

#include <vector>

#include "absl/status/statusor.h"
#include "client/cli/arg_parser.h"
#include "client/io/mesh_io.h"

namespace tetrefine::cli {

// --vtu-compression none|zlib|lzma|lz4, --vtu-encoding appended|base64|ascii, --binary, --ascii,
// with their help. The defaults are the CLI's (MeshWriteOptionsFromArgs).
std::vector<FlagSpec> MeshWriteFlagSpecs();

// The io::MeshWriteOptions `args` ask for. Defaults: .vtu as ParaView's "Save Data" writes it
// (appended raw, zlib: io::VtuWriteOptions{}); .msh and .vtk binary. Errors are
// INVALID_ARGUMENT naming the flag and quoting the value ("--vtu-compression: unknown value
// 'gzip' (known: none, zlib, lzma, lz4)"), or naming both of --binary and --ascii.
absl::StatusOr<io::MeshWriteOptions> MeshWriteOptionsFromArgs(const ParsedArgs& args);

}  // namespace tetrefine::cli
