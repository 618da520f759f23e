"""Issue 15's "done when": in a fresh venv over Debian's packages, `pip install ./python` and the
ten-line script examples/python/refine_demo.py refine the example exactly as the CLI does.

Offline: pip's index is an address nothing listens on, so any download would fail the install.
"""

import os
import shutil
import subprocess
import sys

import meshio
import numpy as np

from conftest import EXAMPLE_MESH, EXAMPLE_VOLUME, ROOT
from test_refine import run_cli

DEMO = os.path.join(ROOT, "examples", "python", "refine_demo.py")


def test_pip_install_and_the_ten_line_script_match_the_cli(server, server_binary, cli_binary,
                                                           tmp_path):
    with open(DEMO) as f:
        assert len(f.read().splitlines()) <= 12, "the demo script is meant to stay that short"
    # Debian's interpreter, whatever runs pytest: the venv is made over its packages.
    python = "/usr/bin/python3" if os.path.exists("/usr/bin/python3") else sys.executable
    venv = tmp_path / "venv"
    subprocess.run([python, "-m", "venv", "--system-site-packages", str(venv)], check=True)
    # A copy, so that the build's egg-info and build/ land there and not in the checkout.
    source = tmp_path / "checkout" / "python"
    shutil.copytree(os.path.join(ROOT, "python"), source,
                    ignore=shutil.ignore_patterns("__pycache__", "build", "*.egg-info"))
    offline = dict(os.environ, PIP_INDEX_URL="http://127.0.0.1:9/",
                   PIP_DISABLE_PIP_VERSION_CHECK="1", PIP_NO_CACHE_DIR="1")
    offline.pop("PYTHONPATH", None)
    install = subprocess.run([str(venv / "bin" / "pip"), "install", "--no-build-isolation",
                              "./python"], cwd=source.parent, env=offline, capture_output=True,
                             text=True, timeout=300)
    assert install.returncode == 0, install.stdout + install.stderr

    where = subprocess.run([str(venv / "bin" / "python"), "-c",
                            "import tetrefine; print(tetrefine.__file__)"], cwd=tmp_path,
                           env=offline, capture_output=True, text=True, check=True).stdout
    assert where.startswith(str(venv)), where

    demo = subprocess.run([str(venv / "bin" / "python"), DEMO, server.target,
                           str(tmp_path / "python.vtu")], cwd=tmp_path, env=offline,
                          capture_output=True, text=True, timeout=300)
    assert demo.returncode == 0, demo.stdout + demo.stderr
    assert demo.stdout.splitlines()[0].startswith("1 "), demo.stdout  # iteration 1's line

    # The installed package runs a server of its own too (tetrefine.LocalServer).
    local = subprocess.run(
        [str(venv / "bin" / "python"), "-c",
         "import sys, tetrefine\n"
         "with tetrefine.LocalServer(sys.argv[1]) as s, s.client() as c:\n"
         "    print(c.server_info().version)", server_binary],
        cwd=tmp_path, env=offline, capture_output=True, text=True, timeout=120)
    assert local.returncode == 0 and local.stdout.strip(), local.stdout + local.stderr

    run_cli(cli_binary, "refine", "--server", server.target, "--volume", EXAMPLE_VOLUME,
            "--mesh", EXAMPLE_MESH, "--fit-mesh-to-volume", "--epsilon", "0.1", "--quiet",
            "--output", str(tmp_path / "cli.vtu"))
    ours, cli = meshio.read(tmp_path / "python.vtu"), meshio.read(tmp_path / "cli.vtu")
    np.testing.assert_array_equal(ours.points, cli.points)
    np.testing.assert_array_equal(ours.cells_dict["tetra"], cli.cells_dict["tetra"])
    for name in ("value",):
        np.testing.assert_array_equal(ours.point_data[name], cli.point_data[name])
    for name in ("iteration", "quality", "medit:ref"):
        np.testing.assert_array_equal(ours.cell_data[name][0], cli.cell_data[name][0])
    assert len(cli.cells_dict["tetra"]) > 1782
