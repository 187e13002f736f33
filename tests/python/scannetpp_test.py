"""open_dataset(root, "scannetpp", device=...) on occgt's ScanNet++-layout fixture (occgt synth
--layout scannetpp): the iPhone frames load as undistorted pinhole frames (depth at the
working size with K of the undistorted camera, anonymised pixels without depth, colour
undistorted), the DSLR frames list with their cameras, and a bad device is a ValueError."""
from __future__ import annotations

import os
import sys
import unittest

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
import common  # noqa: E402

import occgt  # noqa: E402


class ScanNetPP(unittest.TestCase):
    root: str

    @classmethod
    def setUpClass(cls) -> None:
        cls.root = common.scratch("scannetpp")
        common.occgt("synth", "--out", cls.root, "--layout", "scannetpp", "--scenes", "1", "--frames", "4",
                     "--resolution", "160x120", "--seed", "2")

    def test_iphone_frames_load_undistorted(self) -> None:
        dataset = occgt.open_dataset(self.root, "scannetpp", device="iphone")
        self.assertEqual(dataset.scenes(), ["synthpp_000"])
        scene = dataset.scene("synthpp_000")
        usable = [f for f in scene.frames if f.usable]
        self.assertEqual(len(usable), 4)
        self.assertEqual([f.reason for f in scene.frames if not f.usable],
                         ["pose: image not in the COLMAP model"])
        depth, K, world_from_cam = scene.load(usable[1].id, 128, 96)
        self.assertEqual(depth.shape, (96, 128))
        self.assertEqual(depth.dtype, np.float32)
        # The undistorted camera's principal point is centred (getOptimalNewCameraMatrix with
        # centerPrincipalPoint), in OpenCV's convention at 256 x 192, then resized.
        self.assertAlmostEqual(K[0, 2], (128 - 1) / 2, places=9)
        self.assertGreater(float((depth > 0).mean()), 0.6)
        # Frame 1 has an anonymised rectangle: a block of its depth is zero.
        self.assertGreater(int((depth == 0).sum()), 50)
        rgb = scene.load_color(usable[1].id, 128, 96)
        self.assertEqual(rgb.shape, (96, 128, 3))
        self.assertGreater(float(rgb.std()), 5.0)

    def test_dslr_frames_and_bad_device(self) -> None:
        scene = occgt.open_dataset(self.root, "scannetpp").scene("synthpp_000")
        self.assertEqual(len(scene.frames), 6)
        frame = next(f for f in scene.frames if f.usable)
        self.assertEqual((frame.width, frame.height), (160, 120))
        self.assertEqual(float(frame.K[0, 2]), 80.0)
        with self.assertRaises(ValueError):
            occgt.open_dataset(self.root, "scannetpp", device="kinect")


if __name__ == "__main__":
    unittest.main()
