"""The examples of docs/PYTHON.md run as written: every ```python block, in order, in one
namespace, from the project folder (so the default ../shared/data resolves) with
OCCGT_SHARED_DATA set; the real 7-Scenes sample is required."""
from __future__ import annotations

import contextlib
import io
import os
import re
import sys
import unittest
from typing import Any, Dict, List

sys.path.insert(0, os.path.dirname(__file__))
import common  # noqa: E402


def python_blocks(path: str) -> List[str]:
    with open(path) as f:
        text = f.read()
    return re.findall(r"^```python\n(.*?)^```", text, flags=re.S | re.M)


class Docs(unittest.TestCase):
    def test_examples_run(self) -> None:
        common.shared("sevenscenes")
        blocks = python_blocks(os.path.join(common.SOURCE, "docs", "PYTHON.md"))
        self.assertGreaterEqual(len(blocks), 2)
        namespace: Dict[str, Any] = {"__name__": "__docs__"}
        out = io.StringIO()
        cwd = os.getcwd()
        os.chdir(common.SOURCE)
        try:
            for k, block in enumerate(blocks):
                with self.subTest(block=k), contextlib.redirect_stdout(out):
                    exec(compile(block, f"docs/PYTHON.md block {k}", "exec"), namespace)
        finally:
            os.chdir(cwd)
        printed = out.getvalue()
        sys.stdout.write(printed)
        self.assertRegex(printed, r"overlap 0->1 0\.\d+, occlusion 0\.\d+")
        self.assertIn("OUT_OF_VIEW VISIBLE", printed)
        # Scene.fuse's map read by pair_ground_truth as the text says (the scene's depth range).
        self.assertRegex(printed, r"<occgt.ScopeMap rgbd-frames window:1 \(\d+ frames\)> "
                                  r"known bins: [1-9]\d*")
        self.assertRegex(printed, r"view 0: 0\.\d\d of its pixels seen by all 3 others")
        self.assertRegex(printed, r"tracks \(4, 256, 2\) visible in every view: \d+")
        # Rendered depth: the TSDF mesh reproduces the sensor within millimetres, fills holes.
        median = re.search(r"median \|sensor - mesh\| ([0-9.]+) m over (\d+) pixels", printed)
        self.assertIsNotNone(median, printed)
        self.assertLess(float(median.group(1)), 0.01)
        valid = re.search(r"valid pixels: sensor (\d+), fused (\d+)", printed)
        self.assertIsNotNone(valid, printed)
        self.assertGreater(int(valid.group(2)), int(valid.group(1)) * 0.95)
        self.assertIn("depth0: expected a depth map of dtype float32 or float64", printed)
        # The training loop over a LoFTR index saw all 4 pairs, with matches and a finite loss.
        losses = re.findall(r"batch \[(\d+), (\d+)\]: (\d+) matches \((\d+) vv\), loss ([0-9.]+)",
                            printed)
        self.assertEqual(sorted(int(i) for row in losses for i in row[:2]), [0, 1, 2, 3])
        self.assertTrue(all(int(row[2]) > 0 and float(row[4]) > 0 for row in losses), losses)


if __name__ == "__main__":
    unittest.main(verbosity=2)
