#!/usr/bin/env bash
# The README's first command: from a fresh Debian 12 machine, install what tetrefine needs, build
# it, and refine the bundled example (a small brain MRI and an unstructured unit-cube tet mesh)
# with the service embedded in the `tetrefine` process, printing the paper's tables.
# Output goes to out/ (gitignored). TETREFINE_BUILD_DIR overrides the build directory (build).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
build="${TETREFINE_BUILD_DIR:-build}"
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release
cmake --build "$build" -j "$(nproc)" --target tetrefine tetrefine_server
tetrefine="$build/client/tetrefine"
mkdir -p out

echo
echo "== The inputs"
"$tetrefine" info examples/anatomical_33x41x25.nii
echo
"$tetrefine" info examples/unit_cube_1782tets.mesh

# The cube mesh is in unit coordinates; --fit-mesh-to-volume stretches it over the volume's world
# box (RAS mm) less one voxel on every side.
echo
echo "== tetrefine refine (epsilon 0.1, service embedded)"
"$tetrefine" refine \
  --volume examples/anatomical_33x41x25.nii \
  --mesh examples/unit_cube_1782tets.mesh --fit-mesh-to-volume \
  --epsilon 0.1 \
  --output out/anatomical_cube.refined.vtu \
  --stats-json out/anatomical_cube.stats.json

echo
echo "== tetrefine verify of the result"
"$tetrefine" verify --volume examples/anatomical_33x41x25.nii \
  --mesh out/anatomical_cube.refined.vtu --epsilon 0.1

echo
echo "== tetrefine slice: the plane z = 8 mm before and after (the README's picture)"
"$tetrefine" slice --volume examples/anatomical_33x41x25.nii \
  --mesh examples/unit_cube_1782tets.mesh --fit-mesh-to-volume \
  --mesh-after out/anatomical_cube.refined.vtu --axis z --position 8 \
  --output out/anatomical_cube.slice_z8.png

echo
echo "Done: out/anatomical_cube.refined.vtu (open it in ParaView: point data 'value', cell data"
echo "'iteration' and 'quality'), out/anatomical_cube.stats.json and out/anatomical_cube.slice_z8.png."
