"""occgt.views_ground_truth (docs/MULTIVIEW.md): for every ordered pair i != j, bit j of
visible_in[i] / occluded_in[i] equals pair_ground_truth's label01 of (i, j) == VISIBLE /
OCCLUDED bit for bit, and the diagonal bit i of view i is the view's depth mask `valid`
(never OCCLUDED), on the real 7-Scenes and TartanAir samples (read by occgt's readers,
required) and on a synthetic room of `occgt synth`, for several presets; tracks: states equal
label01 at the query pixels in the other views and VISIBLE at the query pixel itself in the
query view, positions equal a float64 projection done here (to float rounding), sampling is
seeded; statistics; list or stacked input; bad inputs raise ValueError naming the
argument."""
from __future__ import annotations

import unittest
from typing import Any, Dict, List, Tuple

import numpy as np

import common
import occgt

Frames = Tuple[List[np.ndarray], List[np.ndarray], List[np.ndarray]]


def load(scene: occgt.Scene, ids: List[str], width: int, height: int) -> Frames:
    depths, Ks, poses = [], [], []
    for i in ids:
        d, K, T = scene.load(i, width=width, height=height)
        depths.append(d)
        Ks.append(K)
        poses.append(T)
    return depths, Ks, poses


def check_against_pairs(case: unittest.TestCase, frames: Frames, range_: Tuple[float, float],
                        **options: Any) -> Dict[str, int]:
    """Asserts the bits equal label01 of every ordered pair; returns the bits counted."""
    depths, Ks, poses = frames
    n = len(depths)
    tracking = {k: options.pop(k) for k in ("query_view", "num_tracks", "seed") if k in options}
    t = occgt.views_ground_truth(depths, Ks, poses, dataset_depth_range=range_, **tracking,
                                 **options)
    case.assertEqual(t["visible_in"].shape, (n,) + depths[0].shape)
    case.assertEqual(t["visible_in"].dtype, np.uint32)
    case.assertEqual(t["occluded_in"].dtype, np.uint32)
    counts = {"visible": 0, "occluded": 0}
    for i in range(n):
        # The diagonal: the view's own depth mask, never occluded.
        np.testing.assert_array_equal((t["visible_in"][i] >> i) & 1, t["valid"][i],
                                      err_msg=f"{i}->{i}")
        case.assertFalse(np.any((t["occluded_in"][i] >> i) & 1))
        for j in range(n):
            if j == i:
                continue
            p = occgt.pair_ground_truth(depths[i], depths[j], Ks[i], Ks[j], poses[i], poses[j],
                                        dataset_depth_range=range_, **options)
            label = p["label01"]
            vis = ((t["visible_in"][i] >> j) & 1).astype(bool)
            occ = ((t["occluded_in"][i] >> j) & 1).astype(bool)
            np.testing.assert_array_equal(vis, label == occgt.VISIBLE, err_msg=f"{i}->{j}")
            np.testing.assert_array_equal(occ, label == occgt.OCCLUDED, err_msg=f"{i}->{j}")
            counts["visible"] += int(vis.sum())
            counts["occluded"] += int(occ.sum())
            # Tracks of the query view: the state is label01 at the query pixel.
            if i == t["query_view"]:
                u, v = t["queries"][:, 0], t["queries"][:, 1]
                expected = np.array([occgt.TRACK_STATE_NAMES.index(
                    {"UNKNOWN": "NO_DEPTH"}.get(occgt.LABEL_NAMES[c], occgt.LABEL_NAMES[c]))
                    for c in label[v, u]], dtype=np.uint8)
                np.testing.assert_array_equal(t["track_state"][j], expected)
    # In the query view itself, a valid query is VISIBLE at its own pixel with its own depth.
    q, u, v = t["query_view"], t["queries"][:, 0], t["queries"][:, 1]
    ok = t["valid"][q][v, u] == 1
    np.testing.assert_array_equal(
        t["track_state"][q], np.where(ok, occgt.TRACK_VISIBLE, occgt.TRACK_NO_DEPTH))
    np.testing.assert_array_equal(t["track_xy"][q][ok], t["queries"][ok].astype(np.float32))
    np.testing.assert_array_equal(t["track_depth"][q][ok], depths[q][v, u][ok])
    case.assertTrue(np.all(np.isnan(t["track_xy"][q][~ok])))
    case.assertTrue(np.all(t["visible_in"] >> n == 0))
    return counts


def project(depth: np.ndarray, K: np.ndarray, world_from_a: np.ndarray, world_from_b: np.ndarray,
            K_b: np.ndarray, uv: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
    """float64 reference: pixels uv of A with their depth -> (x, y) in B and z."""
    d = depth[uv[:, 1], uv[:, 0]].astype(np.float64)
    p = np.stack([(uv[:, 0] - K[0, 2]) / K[0, 0] * d, (uv[:, 1] - K[1, 2]) / K[1, 1] * d, d])
    b_from_a = np.linalg.inv(world_from_b) @ world_from_a
    q = b_from_a[:3, :3] @ p + b_from_a[:3, 3:4]
    x = K_b[0, 0] * q[0] / q[2] + K_b[0, 2]
    y = K_b[1, 1] * q[1] / q[2] + K_b[1, 2]
    return np.stack([x, y], axis=1), q[2]


class RealSamples(unittest.TestCase):
    def test_sevenscenes(self) -> None:
        ds = occgt.open_dataset(common.shared("sevenscenes"), "sevenscenes")
        scene = ds.scene("rgbd-frames")
        ids = [f.id for f in scene.frames if f.usable][::8][:6]
        self.assertEqual(len(ids), 6)
        frames = load(scene, ids, 320, 240)
        rng = (scene.min_depth_m, scene.max_depth_m)
        c = check_against_pairs(self, frames, rng)
        self.assertGreater(c["visible"], 10000)
        self.assertGreater(c["occluded"], 10)
        c = check_against_pairs(self, frames, rng, preset="occ2net", abs_tol_m=0.05)
        self.assertGreater(c["visible"], 10000)

    def test_tartanair(self) -> None:
        ds = occgt.open_dataset(common.shared("tartanair/hospital_sample"), "tartanair")
        scene = ds.scene(ds.scenes()[0])
        ids = [f.id for f in scene.frames if f.usable][::3][:5]
        self.assertEqual(len(ids), 5)
        frames = load(scene, ids, 320, 240)
        c = check_against_pairs(self, frames, (scene.min_depth_m, scene.max_depth_m),
                                preset="loftr")
        self.assertGreater(c["visible"], 10000)


class Synthetic(unittest.TestCase):
    @classmethod
    def setUpClass(cls) -> None:
        root = common.synth_dataset("views_synth", frames=16, resolution="160x120")
        ds = occgt.open_dataset(root, "generic")
        cls.scene = ds.scene(ds.scenes()[0])
        cls.ids = [f.id for f in cls.scene.frames][::2]
        cls.frames = load(cls.scene, cls.ids, 160, 120)
        cls.range = (cls.scene.min_depth_m, cls.scene.max_depth_m)

    def test_every_ordered_pair_every_preset(self) -> None:
        for preset in ("default", "superglue", "occ2net-compat"):
            with self.subTest(preset=preset):
                c = check_against_pairs(self, self.frames, self.range, preset=preset,
                                        query_view=3, num_tracks=64, seed=5)
                self.assertGreater(c["visible"], 1000)
                self.assertGreater(c["occluded"], 10)

    def test_tracks_are_the_warps(self) -> None:
        depths, Ks, poses = self.frames
        t = occgt.views_ground_truth(depths, Ks, poses, num_tracks=200, query_view=2, seed=1,
                                     dataset_depth_range=self.range)
        q = t["queries"]
        self.assertEqual((q.shape, q.dtype), ((200, 2), np.int32))
        raster = q[:, 1] * 160 + q[:, 0]
        self.assertTrue(np.all(np.diff(raster) > 0))  # distinct, raster order
        self.assertTrue(np.all(t["valid"][2][q[:, 1], q[:, 0]] == 1))
        self.assertEqual(t["track_xy"].shape, (len(depths), 200, 2))
        self.assertEqual(t["track_xy"].dtype, np.float32)
        for j in range(len(depths)):
            xy, z = project(depths[2], Ks[2], poses[2], poses[j], Ks[j], q)
            ok = z > self.range[0]
            np.testing.assert_allclose(t["track_xy"][j][ok], xy[ok], atol=2e-3, rtol=1e-4)
            np.testing.assert_allclose(t["track_depth"][j][ok], z[ok], atol=1e-5, rtol=1e-5)
            self.assertTrue(np.all(np.isnan(t["track_xy"][j][~ok])))
        # In its own view a track is exactly where it started, visible.
        np.testing.assert_array_equal(t["track_xy"][2], q.astype(np.float32))
        self.assertTrue(np.all(t["track_state"][2] == occgt.TRACK_VISIBLE))
        # Seeded: the same seed the same queries, another seed others.
        again = occgt.views_ground_truth(depths, Ks, poses, num_tracks=200, query_view=2,
                                         seed=1, dataset_depth_range=self.range)
        np.testing.assert_array_equal(again["queries"], q)
        other = occgt.views_ground_truth(depths, Ks, poses, num_tracks=200, query_view=2,
                                         seed=2, dataset_depth_range=self.range)
        self.assertFalse(np.array_equal(other["queries"], q))
        # Given queries are tracked as given.
        given = np.array([[0, 0], [159, 119], [80, 60]], dtype=np.int64)
        g = occgt.views_ground_truth(depths, Ks, poses, queries=given, query_view=2,
                                     dataset_depth_range=self.range)
        np.testing.assert_array_equal(g["queries"], given)
        self.assertEqual(g["track_state"].shape, (len(depths), 3))
        # The sampled queries given back: the same tracks, bit for bit.
        same = occgt.views_ground_truth(depths, Ks, poses, queries=q, query_view=2,
                                        dataset_depth_range=self.range)
        for key in ("track_xy", "track_depth", "track_state"):
            np.testing.assert_array_equal(same[key], t[key], err_msg=key)

    def test_statistics_and_stacked_input(self) -> None:
        depths, Ks, poses = self.frames
        n = len(depths)
        t = occgt.views_ground_truth(depths, Ks, poses, dataset_depth_range=self.range)
        s = occgt.views_ground_truth(np.stack(depths), np.stack(Ks), np.stack(poses),
                                     dataset_depth_range=self.range)
        for key in ("visible_in", "occluded_in", "valid", "seen_by", "seen_by_histogram",
                    "queries", "track_state"):
            np.testing.assert_array_equal(t[key], s[key], err_msg=key)
        others = t["visible_in"] & ~(np.uint32(1) << np.arange(n, dtype=np.uint32))[:, None, None]
        popcount = np.zeros(others.shape, np.uint8)
        for j in range(n):
            popcount += ((others >> j) & 1).astype(np.uint8)
        np.testing.assert_array_equal(t["seen_by"], popcount)
        for i in range(n):
            valid = t["valid"][i] == 1
            np.testing.assert_array_equal(valid, (depths[i] >= self.range[0])
                                          & (depths[i] <= self.range[1]) & np.isfinite(depths[i]))
            hist = np.bincount(t["seen_by"][i][valid], minlength=n)
            np.testing.assert_array_equal(t["seen_by_histogram"][i], hist)
        self.assertEqual(t["label_options"], occgt.pair_options(
            dataset_depth_range=self.range)["label_options"])

    def test_bad_inputs(self) -> None:
        depths, Ks, poses = self.frames
        d, K, T = depths[0], Ks[0], poses[0]
        cases = [
            (([d] * 33, [K] * 33, [T] * 33), {}, "depths: expected 1..32 depth maps, got 33"),
            (([], [], []), {}, "depths: expected 1..32 depth maps, got 0"),
            (([d, d], [K], [T, T]), {}, "Ks: expected 2 matrices (one per depth map), got 1"),
            (([d, d], [K, K], [T]), {}, "world_from_cams: expected 2 poses"),
            (([d, d[:60]], [K, K], [T, T]), {}, "depths[1]: expected (120, 160)"),
            (([d, d], [K, K], [T, T * 2]), {}, "world_from_cams[1]: "),
            (([d, d], [K, np.zeros((3, 3))], [T, T]), {}, "Ks[1]: "),
            ((np.stack([d, d])[None], [K, K], [T, T]), {}, "depths: expected a list of arrays"),
            (([d, d], [K, K], [T, T]), {"query_view": 2}, "query_view: expected 0..1, got 2"),
            (([d, d], [K, K], [T, T]), {"queries": np.array([[160, 0]])}, "queries: expected"),
            (([d, d], [K, K], [T, T]), {"queries": np.zeros((2, 2), np.float32)},
             "queries: expected an integer array [Q, 2]"),
            (([d, d], [K, K], [T, T]), {"queries": np.zeros((2, 3), np.int32)},
             "queries: expected an integer array [Q, 2]"),
            (([d, d], [K, K], [T, T]), {"num_tracks": -1}, "num_tracks: expected >= 0"),
            (([d, d], [K, K], [T, T]), {"preset": "nope"}, "preset: "),
            (([d, d], [K, K], [T, T]), {"abs_tol_m": -1.0}, "options: "),
        ]
        for args, kwargs, message in cases:
            with self.subTest(message=message):
                with self.assertRaises(ValueError) as e:
                    occgt.views_ground_truth(*args, **kwargs)
                self.assertIn(message, str(e.exception))
        with self.assertRaises(TypeError):
            occgt._occgt.views_ground_truth([d], [K], [T], stride=8)


if __name__ == "__main__":
    unittest.main()
