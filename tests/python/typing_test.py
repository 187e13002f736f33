"""The package's type hints hold: mypy (Debian's `mypy`, installed by `scripts/setup.sh
--test`) checks the package of the build tree (python/occgt with its stubs _occgt.pyi, as a
user's type checker sees it after `pip install`) with no error."""
from __future__ import annotations

import os
import subprocess
import sys
import unittest

sys.path.insert(0, os.path.dirname(__file__))
import common  # noqa: E402


class Typing(unittest.TestCase):
    def test_mypy_clean(self) -> None:
        package = os.path.join(common.BUILD, "python", "occgt")
        self.assertTrue(os.path.isfile(os.path.join(package, "_occgt.pyi")), package)
        cache = os.path.join(common.SCRATCH, "mypy_cache")
        r = subprocess.run(
            [sys.executable, "-m", "mypy", "--python-version", "3.11", "--ignore-missing-imports",
             "--cache-dir", cache, "--no-error-summary", "--show-error-codes", "occgt"],
            cwd=os.path.dirname(package), capture_output=True, text=True)
        if "No module named mypy" in r.stderr:
            self.fail("mypy is missing: scripts/setup.sh --test installs Debian's mypy")
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)


if __name__ == "__main__":
    unittest.main()
