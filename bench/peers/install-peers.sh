#!/usr/bin/env bash
# The peers the reproduction (tools/reproduce) compares tetrefine with, beyond what
# scripts/install-deps.sh installs: DOLFINx's Plaza refinement (Debian's python3-dolfinx, for
# /usr/bin/python3; it pulls in PETSc and MPI, about 1 GB). CI does not need it: without it the
# reproduction's Plaza rows say "not run" and the Plaza script's test is skipped. Debian 12; safe
# to run again.
set -euo pipefail
export DEBIAN_FRONTEND=noninteractive
SUDO=""
if [ "$(id -u)" != "0" ]; then SUDO="sudo"; fi
packages=(python3-dolfinx python3-numpy)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq "${missing[@]}"
fi
/usr/bin/python3 "$(dirname "$0")/plaza_refine.py" --check
echo "python3-dolfinx $(/usr/bin/python3 -c 'import dolfinx; print(dolfinx.__version__)') is ready"
