"""occgt.pair_ground_truth equals `occgt pair` (and `occgt occupancy`) byte for byte: every
array saved with numpy.save is the file the CLI wrote, the metrics are those of meta.json; on
the real 7-Scenes sample (../shared/data/sevenscenes, required) and on a synthetic scene of
`occgt synth`, for every preset; and the readers (open_dataset, Scene.load) give the frames
the CLI uses."""
from __future__ import annotations

import gc
import os
import sys
import unittest

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
import common  # noqa: E402

import occgt  # noqa: E402

PAIR_7S = ("000150", "000160")


class SevenScenes(unittest.TestCase):
    @classmethod
    def setUpClass(cls) -> None:
        cls.root = common.shared("sevenscenes")
        cls.dataset = occgt.open_dataset(cls.root, "sevenscenes")
        cls.scene_name = cls.dataset.scenes()[0]
        cls.scene = cls.dataset.scene(cls.scene_name)

    def test_reader(self) -> None:
        self.assertEqual(self.dataset.scenes(), ["rgbd-frames"])
        frames = self.scene.frames
        self.assertEqual(len(frames), 50)
        ids = [f.id for f in frames]
        self.assertIn(PAIR_7S[0], ids)
        f = frames[ids.index(PAIR_7S[0])]
        self.assertTrue(f.usable)
        self.assertEqual(f.reason, "")
        self.assertEqual((f.width, f.height), (640, 480))
        self.assertEqual(f.K.shape, (3, 3))
        self.assertEqual(f.world_from_cam.shape, (4, 4))
        self.assertEqual((self.scene.min_depth_m, self.scene.max_depth_m), (0.1, 10.0))
        depth, K, pose = self.scene.load(f.id)
        self.assertEqual((depth.dtype, depth.shape), (np.float32, (480, 640)))
        self.assertTrue(depth.flags.writeable and depth.flags.c_contiguous)
        self.assertTrue(np.array_equal(K, f.K))  # depth resolution: K unchanged
        self.assertTrue(np.array_equal(pose, f.world_from_cam))
        self.assertGreater(float(np.mean(depth > 0)), 0.5)
        # Another working resolution: nearest-neighbour depth, K with the pixel-area rule.
        small, K2, _ = self.scene.load(f.id, width=320, height=240)
        self.assertEqual(small.shape, (240, 320))
        # Target pixel u' takes source pixel floor((u' + 0.5) / 0.5) = 2 u' + 1.
        self.assertTrue(np.array_equal(small, depth[1::2, 1::2]))
        self.assertAlmostEqual(K2[0, 0], f.K[0, 0] / 2)
        self.assertAlmostEqual(K2[0, 2], 0.5 * (f.K[0, 2] + 0.5) - 0.5)

    def test_every_preset_equals_cli(self) -> None:
        self.assertEqual(sorted(occgt.PRESETS), sorted(common.PRESETS))
        d0, K0, T0 = self.scene.load(PAIR_7S[0])
        d1, K1, T1 = self.scene.load(PAIR_7S[1])
        for preset in common.PRESETS:
            with self.subTest(preset=preset):
                out = common.scratch(f"7s_{preset}")
                common.pair_cli(self.root, "sevenscenes", self.scene_name, ",".join(PAIR_7S),
                                out, ["--preset", preset])
                r = occgt.pair_ground_truth(d0, d1, K0, K1, T0, T1, preset,
                                            min_depth_m=self.scene.min_depth_m,
                                            max_depth_m=self.scene.max_depth_m)
                meta = common.assert_same_as_pair_folder(self, r, out, f"7-Scenes {preset}")
                self.assertEqual(K0.tolist(), meta["K0"])
                self.assertEqual(K1.tolist(), meta["K1"])
                self.assertEqual(T0.tolist(), meta["world_from_cam0"])
                self.assertEqual(T1.tolist(), meta["world_from_cam1"])
                self.assertGreater(r["matches"].shape[0], 100)  # not vacuous
                self.assertGreater(r["metrics01"]["counts"]["VISIBLE"], 10000)
                r2 = occgt.pair_from_scene(self.scene, *PAIR_7S, preset=preset)
                common.assert_same_as_pair_folder(self, r2, out, f"pair_from_scene {preset}")

    def test_overrides_equal_cli(self) -> None:
        out = common.scratch("7s_overrides")
        common.pair_cli(self.root, "sevenscenes", self.scene_name, ",".join(PAIR_7S), out,
                        ["--preset", "occ2net", "--resolution", "320x240", "--abs-tol-m", 0.05,
                         "--rel-tol", 0.02, "--relative-to", "observed", "--bounds", "pixel-area",
                         "--target-lookup", "nearest", "--missing-target", "as-zero-depth",
                         "--min-depth-m", 0.3, "--max-depth-m", 4, "--stride", 16, "--anchor",
                         "corner", "--no-mutual"])
        r = occgt.pair_from_scene(self.scene, *PAIR_7S, width=320, height=240, preset="occ2net",
                                  abs_tol_m=0.05, rel_tol=0.02, relative_to="observed",
                                  bounds="pixel-area", target_lookup="nearest",
                                  missing_target="as-zero-depth", min_depth_m=0.3,
                                  max_depth_m=4.0, stride=16, anchor="corner", mutual=False)
        meta = common.assert_same_as_pair_folder(self, r, out, "7-Scenes overrides")
        self.assertEqual(r["cells0"].shape, (15, 20))
        self.assertEqual(meta["patch_options"], {"stride": 16, "anchor": "corner", "mutual": False})

    def test_input_layouts(self) -> None:
        """float64 and non-contiguous depth maps, float32 K and poses: the same result."""
        d0, K0, T0 = self.scene.load(PAIR_7S[0])
        d1, K1, T1 = self.scene.load(PAIR_7S[1])
        ref = occgt.pair_ground_truth(d0, d1, K0, K1, T0, T1)
        padded = np.zeros((480, 2 * 640), np.float32)
        padded[:, ::2] = d0  # a strided view below
        variants = {
            "float64": (d0.astype(np.float64), d1),
            "fortran": (np.asfortranarray(d0), np.asfortranarray(d1.astype(np.float64))),
            "strided": (padded[:, ::2], d1),
            "big-endian": (d0.astype(">f4"), d1),
        }
        for name, (a, b) in variants.items():
            with self.subTest(layout=name):
                r = occgt.pair_ground_truth(a, b, K0, K1, T0, T1)
                for key in common.PAIR_ARRAYS + ["T_0to1"]:
                    self.assertEqual(common.npy_bytes(r[key]), common.npy_bytes(ref[key]), key)
                self.assertEqual(r["metrics01"], ref["metrics01"])
        # K given as a list of ints and float32: fx, cx of 7-Scenes are integers.
        r = occgt.pair_ground_truth(d0, d1, K0.astype(np.int64).tolist(), K1.astype(np.float32),
                                    T0, T1)
        self.assertEqual(common.npy_bytes(r["label01"]), common.npy_bytes(ref["label01"]))

    def test_outputs_own_their_memory(self) -> None:
        d0, K0, T0 = self.scene.load(PAIR_7S[0])
        d1, K1, T1 = self.scene.load(PAIR_7S[1])
        r = occgt.pair_ground_truth(d0, d1, K0, K1, T0, T1)
        expected = {"label01": (np.uint8, (480, 640)), "label10": (np.uint8, (480, 640)),
                    "matches": (np.int32, None), "match_type": (np.uint8, None),
                    "match_xy": (np.float32, None), "cells0": (np.uint8, (60, 80)),
                    "cells1": (np.uint8, (60, 80)), "T_0to1": (np.float64, (4, 4))}
        m = r["match_type"].shape[0]
        for key, (dtype, shape) in expected.items():
            a = r[key]
            self.assertEqual(a.dtype, dtype, key)
            if shape is None:
                shape = (m, 2) if key != "match_type" else (m,)
            self.assertEqual(a.shape, shape, key)
            self.assertTrue(a.flags.c_contiguous and a.flags.writeable, key)
        # The label map is the C++ vector itself, owned through a capsule (no copy).
        self.assertEqual(type(r["label01"].base).__name__, "PyCapsule")
        labels = r["label01"]
        counts = np.bincount(labels.ravel(), minlength=6).tolist()
        del r
        gc.collect()
        self.assertEqual(np.bincount(labels.ravel(), minlength=6).tolist(), counts)
        T = occgt.pair_ground_truth(d0, d1, K0, K1, T0, T1)["T_0to1"]
        np.testing.assert_allclose(T, np.linalg.inv(T1) @ T0, atol=1e-12)

    def test_different_sizes(self) -> None:
        """The two frames may have different working resolutions (each K at its own size)."""
        d0, K0, T0 = self.scene.load(PAIR_7S[0])
        d1, K1, T1 = self.scene.load(PAIR_7S[1], width=320, height=240)
        r = occgt.pair_ground_truth(d0, d1, K0, K1, T0, T1, occupancy=True, voxel_m=0.1)
        self.assertEqual(r["label01"].shape, (480, 640))
        self.assertEqual(r["label10"].shape, (240, 320))
        self.assertEqual(r["cells0"].shape, (60, 80))
        self.assertEqual(r["cells1"].shape, (30, 40))
        self.assertEqual(r["occ0"].shape, (240, 320))
        self.assertEqual(r["occ1"].shape, (120, 160))
        self.assertEqual(r["metrics01"]["sampled"], 640 * 480)
        self.assertEqual(r["metrics10"]["sampled"], 320 * 240)
        i, j = r["matches"][:, 0], r["matches"][:, 1]
        self.assertGreater(len(i), 100)
        self.assertTrue(np.all((i >= 0) & (i < 60 * 80) & (j >= 0) & (j < 30 * 40)))
        # Same poses, nearly the same geometry: the overlap barely changes with B's size.
        same = occgt.pair_ground_truth(d0, self.scene.load(PAIR_7S[1])[0], K0,
                                       self.scene.load(PAIR_7S[1])[1], T0, T1)
        self.assertAlmostEqual(r["metrics01"]["overlap"], same["metrics01"]["overlap"], delta=0.02)


class Synthetic(unittest.TestCase):
    @classmethod
    def setUpClass(cls) -> None:
        cls.root = common.synth_dataset("synth_pairs", frames=16, resolution="320x240")
        cls.dataset = occgt.open_dataset(cls.root, "generic")
        cls.scene_name = cls.dataset.scenes()[0]
        cls.scene = cls.dataset.scene(cls.scene_name)
        cls.ids = [f.id for f in cls.scene.frames]

    def test_every_preset_equals_cli(self) -> None:
        self.assertEqual(self.scene_name, "synth_000")
        pair = (self.ids[1], self.ids[2])
        for width, height in [(320, 240), (640, 480)]:  # native and resized by the reader
            for preset in common.PRESETS:
                with self.subTest(preset=preset, resolution=(width, height)):
                    out = common.scratch(f"synth_{preset}_{width}")
                    common.pair_cli(self.root, "generic", self.scene_name, ",".join(pair), out,
                                    ["--preset", preset, "--resolution", f"{width}x{height}"])
                    r = occgt.pair_from_scene(self.scene, *pair, width=width, height=height,
                                              preset=preset)
                    common.assert_same_as_pair_folder(self, r, out, f"synth {preset}")
                    self.assertGreater(r["matches"].shape[0], 50)
        # Occlusion is present in the synthetic rooms (poles and panels): vo/ov matches too.
        self.assertGreater(int(np.sum(r["match_type"] != 0)), 0)

    def test_occupancy_equals_cli(self) -> None:
        pair = (self.ids[0], self.ids[1])
        cases = [
            ([], {}),
            (["--voxel-m", 0.1, "--bins", 32, "--near-m", 0.3, "--far-m", 8, "--spacing", "log",
              "--traversal", "center", "--max-range-m", 6],
             dict(voxel_m=0.1, bins=32, near_m=0.3, far_m=8.0, spacing="log", traversal="center",
                  max_range_m=6.0)),
            (["--mode", "two_point", "--spacing", "inverse"],
             dict(occupancy_mode="two_point", spacing="inverse")),
        ]
        for flags, kwargs in cases:
            with self.subTest(flags=flags):
                out = common.scratch("synth_occupancy")
                common.occgt("occupancy", "--root", self.root, "--format", "generic", "--scene",
                             self.scene_name, "--frames", ",".join(pair), "--resolution",
                             "320x240", "--dense", "--out", out, *flags)
                r = occgt.pair_from_scene(self.scene, *pair, width=320, height=240,
                                          occupancy=True, **kwargs)
                common.assert_same_as_folder(self, r, out, common.OCCUPANCY_ARRAYS,
                                             f"occupancy {flags}")
                meta = common.read_json(os.path.join(out, "occupancy.json"))
                self.assertEqual(r["bin_edges_m"].tolist(), meta["bins"]["edges_m"])
                bins = meta["bins"]["num_bins"]
                for cam in "01":
                    dense = occgt.dense_volume(r["occ" + cam], r["known" + cam], bins)
                    self.assertEqual(common.npy_bytes(dense),
                                     common.read_bytes(os.path.join(out, f"occ{cam}_dense.npy")))
                self.assertEqual(r["occ0"].dtype, np.uint64)
                self.assertEqual(r["occ0"].shape, (120, 160))
                self.assertTrue(np.all(r["occ0"] & ~r["known0"] == 0))
                self.assertGreater(int(np.count_nonzero(r["occ0"])), 1000)
        # With occupancy the labels are still those of `occgt pair`.
        out = common.scratch("synth_pair_with_occupancy")
        common.pair_cli(self.root, "generic", self.scene_name, ",".join(pair), out,
                        ["--resolution", "320x240"])
        common.assert_same_as_pair_folder(self, r, out, "labels next to occupancy")

    def test_dense_volume_layout(self) -> None:
        occ = np.array([[0b01, 0b10]], dtype=np.uint64)
        known = np.array([[0b11, 0b10]], dtype=np.uint64)
        dense = occgt.dense_volume(occ, known, bins=3)
        self.assertEqual((dense.dtype, dense.shape), (np.uint8, (3, 1, 2)))
        self.assertEqual(dense[:, 0, 0].tolist(), [1, 0, 255])
        self.assertEqual(dense[:, 0, 1].tolist(), [255, 1, 255])


class SevenScenesOccupancy(unittest.TestCase):
    def test_occupancy_equals_cli(self) -> None:
        root = common.shared("sevenscenes")
        scene = occgt.open_dataset(root, "sevenscenes").scene("rgbd-frames")
        out = common.scratch("7s_occupancy")
        common.occgt("occupancy", "--root", root, "--format", "sevenscenes", "--scene",
                     "rgbd-frames", "--frames", ",".join(PAIR_7S), "--out", out)
        r = occgt.pair_from_scene(scene, *PAIR_7S, occupancy=True)
        common.assert_same_as_folder(self, r, out, common.OCCUPANCY_ARRAYS, "7-Scenes occupancy")
        meta = common.read_json(os.path.join(out, "occupancy.json"))
        self.assertEqual(r["bin_edges_m"].tolist(), meta["bins"]["edges_m"])
        self.assertEqual(r["occ0"].shape, (240, 320))


if __name__ == "__main__":
    unittest.main(verbosity=2)
