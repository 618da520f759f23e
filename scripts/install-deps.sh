#!/usr/bin/env bash
# One install script for the README, CI and the Dockerfile's build stage: what CI exercises is what
# the container build does. Installs Debian 12 packages only; safe to run again.
set -euo pipefail
export DEBIAN_FRONTEND=noninteractive
SUDO=""
if [ "$(id -u)" != "0" ]; then SUDO="sudo"; fi
packages=(
  build-essential cmake ninja-build pkg-config git ca-certificates
  libgrpc++-dev protobuf-compiler-grpc libprotobuf-dev protobuf-compiler
  libabsl-dev libspdlog-dev libtbb-dev zlib1g-dev libpugixml-dev liblzma-dev liblz4-dev libdeflate-dev libisal-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  # The programs' allocator, tcmalloc (cmake/FastAllocator.cmake says why).
  libgoogle-perftools-dev
  prometheus-cpp-dev libssl-dev openssl clang-format
  python3 python3-grpcio python3-numpy python3-meshio python3-yaml
  # The Python package (python/) and its tests: pip install --no-build-isolation in a venv
  # over these needs setuptools and wheel from Debian, nothing from PyPI.
  python3-protobuf python3-venv python3-setuptools python3-wheel python3-pytest python3-nibabel
  # tetrefine slice draws its figures with Cairo and writes them as PNG through it.
  libcairo2-dev
  # tetrefine plot reads refine's --stats-json files with it (header-only).
  nlohmann-json3-dev
)
# Independent readers and writers the tests compare against (VTK 9, Gmsh and TetGen, beside meshio
# above; pydicom writes DICOM series and dcm2niix converts them for the DICOM reader's tests);
# the container's build stage sets TETREFINE_WITH_TEST_TOOLS=0 as it builds no tests.
if [ "${TETREFINE_WITH_TEST_TOOLS:-1}" = "1" ]; then
  packages+=(python3-vtk9 gmsh tetgen python3-pydicom dcm2niix)
fi
# Fuzzing and sanitizer runs (clang's libFuzzer) only when asked: TETREFINE_WITH_FUZZ=1.
if [ "${TETREFINE_WITH_FUZZ:-0}" = "1" ]; then
  packages+=(clang-14 libclang-rt-14-dev llvm-14)
fi
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
