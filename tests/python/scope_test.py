"""Occupancy fused over a window of frames or a whole scene from Python (Scene.fuse,
pair_ground_truth(scope_map=...), pair_from_scene(scope=...)): the occupancy words equal
`occgt occupancy --scope` byte for byte on the real 7-Scenes sample; the map lists what it
fused; mismatched options and bad scopes raise ValueError."""
from __future__ import annotations

import os
import sys
import unittest

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
import common  # noqa: E402

import occgt  # noqa: E402

PAIR = ("000150", "000160")


class Scopes(unittest.TestCase):
    @classmethod
    def setUpClass(cls) -> None:
        cls.root = common.shared("sevenscenes")
        cls.scene = occgt.open_dataset(cls.root, "sevenscenes").scene("rgbd-frames")

    def test_equal_to_cli(self) -> None:
        words = {}
        for scope in ("pair", "window:2", "scene:10"):
            out = common.scratch("scope_" + scope.replace(":", "_"))
            common.occgt("occupancy", "--root", self.root, "--format", "sevenscenes", "--scene",
                         "rgbd-frames", "--frames", ",".join(PAIR), "--scope", scope, "--out",
                         out, "--resolution", "320x240")
            got = occgt.pair_from_scene(self.scene, *PAIR, width=320, height=240, occupancy=True,
                                        scope=scope)
            common.assert_same_as_folder(self, got, out, common.OCCUPANCY_ARRAYS, scope)
            # The returned options name the scope fused over, as a sample's json does.
            self.assertEqual(got["options"]["occupancy_options"]["fusion"]["scope"], scope)
            meta = common.read_json(os.path.join(out, "occupancy.json"))
            fused = self.scene.fuse(*PAIR, 320, 240, scope=scope)
            self.assertEqual(fused.scope, scope)
            self.assertEqual(fused.fused_ids, meta["fusion"]["fused_frames"])
            self.assertEqual(fused.skipped, meta["fusion"]["skipped_frames"])
            self.assertIn(PAIR[0], fused.fused_ids)
            self.assertIn(PAIR[1], fused.fused_ids)
            words[scope] = got["occ0"]
        self.assertEqual(len(self.scene.fuse(*PAIR, 320, 240, scope="pair").fused_ids), 2)
        self.assertGreater(len(self.scene.fuse(*PAIR, 320, 240, scope="window:2").fused_ids), 2)
        # A wider scope knows more of the volume than the pair alone.
        self.assertFalse(np.array_equal(words["pair"], words["window:2"]))

    def test_far_m_is_the_ray_range(self) -> None:
        """max_range_m=None is far_m, as `occgt occupancy --far-m` and a recipe have it."""
        out = common.scratch("scope_far_m")
        common.occgt("occupancy", "--root", self.root, "--format", "sevenscenes", "--scene",
                     "rgbd-frames", "--frames", ",".join(PAIR), "--far-m", "2.5", "--out", out,
                     "--resolution", "160x120")
        got = occgt.pair_from_scene(self.scene, *PAIR, width=160, height=120, occupancy=True,
                                    far_m=2.5)
        common.assert_same_as_folder(self, got, out, common.OCCUPANCY_ARRAYS, "far_m 2.5")
        ten = occgt.pair_from_scene(self.scene, *PAIR, width=160, height=120, occupancy=True,
                                    far_m=2.5, max_range_m=10.0)
        self.assertFalse(np.array_equal(ten["known0"], got["known0"]))
        window = occgt.pair_from_scene(self.scene, *PAIR, width=160, height=120, occupancy=True,
                                       far_m=2.5, scope="window:1")
        self.assertEqual(window["bin_edges_m"][-1], 2.5)

    def test_shared_map_and_errors(self) -> None:
        fused = self.scene.fuse(*PAIR, 160, 120, scope="scene:20", voxel_m=0.1)
        d0, K0, T0 = self.scene.load(PAIR[0], 160, 120)
        d1, K1, T1 = self.scene.load(PAIR[1], 160, 120)
        depth_range = {"min_depth_m": self.scene.min_depth_m, "max_depth_m": self.scene.max_depth_m}
        a = occgt.pair_ground_truth(d0, d1, K0, K1, T0, T1, occupancy=True, voxel_m=0.1,
                                    scope_map=fused, **depth_range)
        b = occgt.pair_from_scene(self.scene, *PAIR, width=160, height=120, occupancy=True,
                                  voxel_m=0.1, scope="scene:20")
        self.assertTrue(np.array_equal(a["known1"], b["known1"]))
        self.assertEqual(a["options"]["occupancy_options"]["fusion"]["scope"], "scene:20")
        self.assertEqual(a["options"], b["options"])
        with self.assertRaisesRegex(ValueError, "scope_map: fused with voxel_m 0.1"):
            occgt.pair_ground_truth(d0, d1, K0, K1, T0, T1, occupancy=True, scope_map=fused)
        with self.assertRaisesRegex(ValueError, "scope_map: given without occupancy=True"):
            occgt.pair_ground_truth(d0, d1, K0, K1, T0, T1, voxel_m=0.1, scope_map=fused)
        # A map of other depth maps than the pair's: another size or depth range (it was used).
        s0, sK0, _ = self.scene.load(PAIR[0], 80, 60)
        s1, sK1, _ = self.scene.load(PAIR[1], 80, 60)
        with self.assertRaisesRegex(ValueError, r"^scope_map: fused at 160x120; expected the "
                                    r"size of depth0 here, 80x60$"):
            occgt.pair_ground_truth(s0, s1, sK0, sK1, T0, T1, occupancy=True, voxel_m=0.1,
                                    scope_map=fused, **depth_range)
        with self.assertRaisesRegex(ValueError, r"^scope_map: fused with depth range \["):
            occgt.pair_ground_truth(d0, d1, K0, K1, T0, T1, occupancy=True, voxel_m=0.1,
                                    scope_map=fused, min_depth_m=0.5,
                                    max_depth_m=self.scene.max_depth_m)
        with self.assertRaisesRegex(ValueError, "^scope: "):
            self.scene.fuse(*PAIR, 160, 120, scope="window")
        with self.assertRaisesRegex(ValueError, r"max_range_m must be finite.* \(max_range_m is "
                                    r"far_m when not given: far_m=nan\)$"):
            self.scene.fuse(*PAIR, 160, 120, far_m=float("nan"))
        with self.assertRaisesRegex(ValueError, "id1"):
            self.scene.fuse(PAIR[0], "999999", 160, 120)
        with self.assertRaises(TypeError):
            occgt.pair_ground_truth(d0, d1, K0, K1, T0, T1, occupancy=True, scope_map="scene")

    def test_scope_beside_a_map(self) -> None:
        """pair_from_scene with scope_map: the map's scope (or "pair", the default) is
        accepted, leading zeros included; another scope is a ValueError (it was ignored
        silently: scope="scene:5" gave the window map's volumes)."""
        window = self.scene.fuse(*PAIR, 80, 60, scope="window:1")
        want = occgt.pair_from_scene(self.scene, *PAIR, width=80, height=60, occupancy=True,
                                     scope="window:1")
        for scope in ("pair", "window:1", "window:01"):
            got = occgt.pair_from_scene(self.scene, *PAIR, width=80, height=60, occupancy=True,
                                        scope=scope, scope_map=window)
            self.assertTrue(np.array_equal(got["occ0"], want["occ0"]), scope)
        for scope in ("scene:5", "window:2"):
            with self.subTest(scope=scope), self.assertRaisesRegex(
                    ValueError, r"^scope: '%s', but scope_map was fused over 'window:1'" % scope):
                occgt.pair_from_scene(self.scene, *PAIR, width=80, height=60, occupancy=True,
                                      scope=scope, scope_map=window)
        with self.assertRaisesRegex(ValueError, r"^scope: expected pair, window:N or "
                                    r"scene:S with N, S >= 1, got 'window:x'$"):
            occgt.pair_from_scene(self.scene, *PAIR, width=80, height=60, occupancy=True,
                                  scope="window:x", scope_map=window)


if __name__ == "__main__":
    unittest.main()
