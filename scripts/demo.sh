#!/usr/bin/env bash
# The README's first command: from a fresh Debian 12 machine, install what tetrefine needs, build
# it, and refine the bundled example (a small brain MRI and an unstructured unit-cube tet mesh)
# with the service embedded in the `tetrefine` process, printing the paper's tables.
# Output goes to out/ (gitignored). TETREFINE_BUILD_DIR overrides the build directory (build).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
build="${TETREFINE_BUILD_DIR:-build}"
# Unity build: see scripts/test.sh.
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_UNITY_BUILD=ON
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
echo "== The paper's scheme on the same input (--scheme paper), for comparison"
"$tetrefine" refine --quiet --scheme paper \
  --volume examples/anatomical_33x41x25.nii \
  --mesh examples/unit_cube_1782tets.mesh --fit-mesh-to-volume \
  --epsilon 0.1 \
  --output out/anatomical_cube.paper.vtu \
  --stats-json out/anatomical_cube.paper.stats.json | grep -E "^(Stopped|Lattice|Edge-midpoint|Wrote)"
python3 - <<'PY'
import json
rows = [("longest-edge (default)", "out/anatomical_cube.stats.json"),
        ("paper", "out/anatomical_cube.paper.stats.json")]
print(f"{'scheme':24} {'iterations':>10} {'tets':>8} {'midpoint max':>12} {'quality min':>11} "
      f"{'mean':>6}  stop")
for name, path in rows:
    s = json.load(open(path))
    q = s["quality"]["final"]
    print(f"{name:24} {len(s['iterations']):>10} {s['output_mesh']['tets']:>8} "
          f"{s['final_max_error']:>12.4f} {q['min']:>11.3g} {q['mean']:>6.3f}  {s['stop_reason']}")
PY

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
echo "== tetrefine plot: error and tets per iteration of both schemes (the README's convergence plot)"
"$tetrefine" plot \
  --stats-json out/anatomical_cube.stats.json --stats-json out/anatomical_cube.paper.stats.json \
  --output out/anatomical_cube.convergence.png

echo
echo "Done: out/anatomical_cube.refined.vtu (open it in ParaView: point data 'value', cell data"
echo "'iteration' and 'quality'), out/anatomical_cube.stats.json, out/anatomical_cube.slice_z8.png"
echo "and out/anatomical_cube.convergence.png."
