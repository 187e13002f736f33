"""The Python package reads ScanNet raw .sens in place: open_dataset(root, "scannet") on a
.sens written by tests/support/write_sens.py gives the same frames, depth, K, poses, colour
and pair ground truth as the exported layout of the same frames (the real 7-Scenes sample
re-packed, and a synthetic scene with JPEG colour and a lost-tracking frame)."""
from __future__ import annotations

import os
import sys
import unittest

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
import common  # noqa: E402

import occgt  # noqa: E402

sys.path.insert(0, os.path.join(common.SOURCE, "tests", "support"))
import write_sens  # noqa: E402


class Sens(unittest.TestCase):
    @classmethod
    def setUpClass(cls) -> None:
        out = common.scratch("sens")
        write_sens.main(["", "synthetic", out])
        write_sens.main(["", "sevenscenes", common.shared("sevenscenes"), out])
        cls.sens = occgt.open_dataset(os.path.join(out, "sens"), "scannet")
        cls.export = occgt.open_dataset(os.path.join(out, "export"), "scannet")

    def test_same_frames_and_pixels(self) -> None:
        self.assertEqual(self.sens.scenes(), ["seven", "synth"])
        for name, size in [("seven", (160, 120)), ("synth", (80, 60))]:
            a, b = self.sens.scene(name), self.export.scene(name)
            self.assertEqual([(f.id, f.usable, f.reason) for f in a.frames],
                             [(f.id, f.usable, f.reason) for f in b.frames])
            details = {f.id: f.detail for f in b.frames}
            for f in a.frames:
                if not f.usable:
                    self.assertIn("lost tracking", f.reason)
                    # Where: the frame's index in the .sens, the pose file's line in the export.
                    self.assertTrue(f.detail.endswith(f"{name}.sens: frame {f.id}: non-finite value"),
                                    f.detail)
                    self.assertTrue(details[f.id].endswith(
                        os.path.join("pose", f.id + ".txt") + ":1: non-finite value"), details[f.id])
                    continue
                for x, y in zip(a.load(f.id, *size), b.load(f.id, *size)):
                    np.testing.assert_array_equal(x, y)
                np.testing.assert_array_equal(a.load_color(f.id, *size), b.load_color(f.id, *size))
            ids = [f.id for f in a.frames if f.usable]
            ga = occgt.pair_from_scene(a, ids[0], ids[-1], width=size[0], height=size[1])
            gb = occgt.pair_from_scene(b, ids[0], ids[-1], width=size[0], height=size[1])
            for key in ["label01", "label10"]:
                np.testing.assert_array_equal(ga[key], gb[key])
            self.assertTrue((ga["label01"] == 2).any())


if __name__ == "__main__":
    unittest.main()
