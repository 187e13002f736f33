"""The package's signatures: mypy (Debian's `mypy`, installed by `scripts/setup.sh --test`)
checks the package of the build tree (python/occgt with its stubs _occgt.pyi, as a user's
type checker sees it after `pip install`) with no error; and no default of an option that
the C++ defines is written in Python (the *_DEFAULTS dicts come from the C++ Options structs,
and the binding's own signatures use the same values)."""
from __future__ import annotations

import ast
import glob
import inspect
import os
import re
import subprocess
import sys
import unittest
from typing import Any, Dict

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
import common  # noqa: E402

import occgt  # noqa: E402
from occgt import _occgt  # noqa: E402

DEFAULTS = {"PAIR_DEFAULTS": occgt.PAIR_DEFAULTS, "VIEWS_DEFAULTS": occgt.VIEWS_DEFAULTS,
            "RENDER_DEFAULTS": occgt.RENDER_DEFAULTS,
            "SUPERVISION_DEFAULTS": occgt.SUPERVISION_DEFAULTS,
            "DATASET_DEFAULTS": occgt.DATASET_DEFAULTS}


def binding_defaults(function: Any) -> Dict[str, Any]:
    """The keyword defaults of a pybind11 function, read from its signature line."""
    line = function.__doc__.splitlines()[0]
    out = {}
    for name, value in re.findall(r"(\w+): [\w.\[\], ]+ = ('[^']*'|[^,)]+)", line):
        try:
            out[name] = ast.literal_eval(value)
        except (ValueError, SyntaxError):
            out[name] = value  # None-like objects pybind11 prints by repr
    return out


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

    def test_no_option_default_is_written_in_python(self) -> None:
        """Every keyword named in a *_DEFAULTS dict takes its default from one (an AST walk
        over the package's sources: no literal default for those names)."""
        names = {k for d in DEFAULTS.values() for k in d}
        self.assertTrue({"num_tracks", "near_m", "coarse_stride", "device", "depth_source",
                         "preset", "bins"} <= names, sorted(names))
        sources = glob.glob(os.path.join(common.SOURCE, "python", "occgt", "**", "*.py"),
                            recursive=True)
        self.assertGreater(len(sources), 5)
        literal = []
        for path in sources:
            with open(path) as f:
                tree = ast.parse(f.read(), path)
            for node in ast.walk(tree):
                if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                    continue
                a = node.args
                positional = (a.posonlyargs + a.args)[len(a.posonlyargs + a.args) - len(a.defaults):]
                pairs = list(zip(positional, a.defaults)) + [
                    (arg, d) for arg, d in zip(a.kwonlyargs, a.kw_defaults) if d is not None]
                for arg, default in pairs:
                    if (arg.arg in names and isinstance(default, ast.Constant) and
                            default.value is not None):
                        literal.append(f"{os.path.relpath(path, common.SOURCE)}:{default.lineno}: "
                                       f"{node.name}({arg.arg}={default.value!r})")
        self.assertEqual(literal, [])

    def test_typed_dicts_name_every_returned_key(self) -> None:
        """PairGroundTruth names every key pair_ground_truth returns (``options`` was
        missing: mypy refused ``gt["options"]``), its required keys without occupancy."""
        K = np.array([[50.0, 0.0, 31.5], [0.0, 50.0, 23.5], [0.0, 0.0, 1.0]])
        wall = np.full((48, 64), 2.0, np.float32)
        keys = occgt.PairGroundTruth.__required_keys__ | occgt.PairGroundTruth.__optional_keys__
        plain = occgt.pair_ground_truth(wall, wall, K, K, np.eye(4), np.eye(4))
        self.assertEqual(set(plain), set(occgt.PairGroundTruth.__required_keys__))
        with_occupancy = occgt.pair_ground_truth(wall, wall, K, K, np.eye(4), np.eye(4),
                                                 occupancy=True)
        self.assertEqual(set(with_occupancy), set(keys))

    def test_defaults_are_the_bindings(self) -> None:
        """The dicts hold what the binding's signatures use, and the wrappers show them."""
        checks = [(_occgt.views_ground_truth, occgt.views_ground_truth, occgt.VIEWS_DEFAULTS),
                  (_occgt.render_depth, occgt.render_depth, occgt.RENDER_DEFAULTS),
                  (_occgt.loftr_coarse_supervision, None, occgt.SUPERVISION_DEFAULTS),
                  (_occgt.Dataset.__init__, occgt.open_dataset, {"device": occgt.DATASET_DEFAULTS["device"]}),
                  (_occgt.dense_volume, occgt.dense_volume, {"bins": occgt.PAIR_DEFAULTS["bins"]})]
        for binding, wrapper, expected in checks:
            got = binding_defaults(binding)
            for key, value in expected.items():
                self.assertEqual(got.get(key), value, f"{binding.__name__}: {key}")
                if wrapper is not None:
                    default = inspect.signature(wrapper).parameters[key].default
                    self.assertEqual(default, value, f"{wrapper.__name__}: {key}")
        self.assertEqual(occgt.DATASET_DEFAULTS["depth_source"], "sensor")
        self.assertEqual(
            inspect.signature(occgt.pair_from_scene).parameters["depth_source"].default,
            occgt.DATASET_DEFAULTS["depth_source"])


if __name__ == "__main__":
    unittest.main()
