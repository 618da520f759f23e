#pragma once

#include <functional>
#include <string>

#include "client/io/volume_file.h"
#include "tests/io/io_test_util.h"

namespace tetrefine::io::iotest {

// Whether /usr/bin/python3 imports vtk and numpy (python3-vtk9).
bool HaveVtkPython();

// Runs the Python `script` (which writes volume files with VTK into the directory it gets as its
// argument) and checks every line it prints, "<file> x y z value": ReadVolume(file) must sample
// `value` at world point (x, y, z) within 1e-9 relative (VTK interpolates in float64 with its own
// weights). `check` sees each file once, when it is first read. Returns the number of files.
int ExpectVolumesSampleAsVtkProbes(
    const std::string& script, const ScratchDir& dir,
    const std::function<void(const std::string& path, const VolumeFile& file)>& check);

}  // namespace tetrefine::io::iotest
