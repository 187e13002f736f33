"""The install command of docs/PYTHON.md, for real: a fresh venv made with
`/usr/bin/python3 -m venv --system-site-packages`, then `pip install --no-build-isolation
./python` (offline: PIP_NO_INDEX forbids any download), then `import occgt` from outside the
source and build trees, without PYTHONPATH: the installed package (module, stubs, py.typed)
computes a pair. The same into a folder (`pip install --target DIR --no-deps`, the
page's other command), imported with PYTHONPATH=DIR."""
from __future__ import annotations

import os
import subprocess
import sys
import unittest

sys.path.insert(0, os.path.dirname(__file__))
import common  # noqa: E402

CHECK = r"""
import os, sys
import numpy as np
import occgt
here = os.path.dirname(occgt.__file__)
prefix = os.environ.get("INSTALLED_UNDER", sys.prefix)
assert here.startswith(prefix), (here, prefix)
files = set(os.listdir(here))
assert {"__init__.py", "_occgt.pyi", "py.typed"} <= files, files
assert any(f.startswith("_occgt.cpython-") and f.endswith(".so") for f in files), files
K = np.array([[50.0, 0, 31.5], [0, 50.0, 23.5], [0, 0, 1]])
T1 = np.eye(4); T1[0, 3] = 0.1
gt = occgt.pair_ground_truth(np.full((48, 64), 2.0, np.float32), np.full((48, 64), 2.0), K, K,
                             np.eye(4), T1, occupancy=True)
assert gt["label01"].shape == (48, 64) and gt["occ0"].shape == (24, 32)
print("installed", occgt.__version__, here)
"""


class Install(unittest.TestCase):
    def run_offline(self, *cmd: str, cwd: str, **extra: str) -> str:
        env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}
        env.update(OCCGT_BUILD_DIR=common.BUILD, PIP_NO_INDEX="1", PIP_NO_INPUT="1",
                   PIP_DISABLE_PIP_VERSION_CHECK="1", **extra)
        r = subprocess.run(list(cmd), cwd=cwd, env=env, capture_output=True, text=True,
                           timeout=600)
        self.assertEqual(r.returncode, 0, f"{' '.join(cmd)}:\n{r.stdout}\n{r.stderr}")
        return r.stdout

    def test_target_folder(self) -> None:
        target = common.scratch("pip_target")
        out = self.run_offline("/usr/bin/python3", "-m", "pip", "install", "--no-build-isolation",
                               "--no-deps", "--target", target, "./python", cwd=common.SOURCE)
        self.assertIn("Successfully installed occgt", out)
        printed = self.run_offline("/usr/bin/python3", "-c", CHECK, cwd=target, PYTHONPATH=target,
                                   INSTALLED_UNDER=target)
        self.assertIn("installed", printed)

    def test_fresh_venv(self) -> None:
        venv = common.scratch("venv")
        run = self.run_offline

        run("/usr/bin/python3", "-m", "venv", "--system-site-packages", venv, cwd=venv)
        out = run(os.path.join(venv, "bin", "pip"), "install", "--no-build-isolation", "./python",
                  cwd=common.SOURCE)
        self.assertIn("Successfully installed occgt", out)
        self.assertFalse(os.path.exists(os.path.join(common.SOURCE, "python", "occgt.egg-info")))
        printed = run(os.path.join(venv, "bin", "python"), "-c", CHECK, cwd=venv)
        self.assertIn("installed", printed)


if __name__ == "__main__":
    unittest.main(verbosity=2)
