"""Bad arguments raise ValueError naming the argument and what was expected, and never crash
the interpreter (each case runs in this process: a crash fails the test). Covers dtypes,
shapes, non-finite and non-rigid poses, bad K, option values and names, the readers and
dense_volume."""
from __future__ import annotations

import json
import os
import pathlib
import re
import sys
import unittest
from typing import Any, Dict

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
import common  # noqa: E402

import occgt  # noqa: E402

H, W = 48, 64


def good() -> Dict[str, Any]:
    """A valid pair: a fronto-parallel wall 2 m away, the second camera 10 cm to the right."""
    K = np.array([[50.0, 0, 31.5], [0, 50.0, 23.5], [0, 0, 1]])
    T1 = np.eye(4)
    T1[0, 3] = 0.1
    return dict(depth0=np.full((H, W), 2.0, np.float32), depth1=np.full((H, W), 2.0, np.float32),
                K0=K, K1=K.copy(), world_from_cam0=np.eye(4), world_from_cam1=T1)


def rot_z(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    T = np.eye(4)
    T[:2, :2] = [[c, -s], [s, c]]
    return T


class BadInput(unittest.TestCase):
    def check(self, pattern: str, **changes: Any) -> None:
        args = good()
        kwargs = {k: changes.pop(k) for k in list(changes) if k not in args}
        args.update(changes)
        with self.assertRaisesRegex(ValueError, pattern):
            occgt.pair_ground_truth(**args, **kwargs)

    def test_good_pair_works(self) -> None:
        # The stable codes of design/GROUND_TRUTH.md §2, §4.
        self.assertEqual((occgt.NO_DEPTH, occgt.OUT_OF_VIEW, occgt.VISIBLE, occgt.OCCLUDED,
                          occgt.INCONSISTENT, occgt.UNKNOWN), (0, 1, 2, 3, 4, 5))
        self.assertEqual((occgt.VV, occgt.VO, occgt.OV), (0, 1, 2))
        r = occgt.pair_ground_truth(**good(), occupancy=True)
        self.assertEqual(r["label01"].shape, (H, W))
        self.assertGreater(r["metrics01"]["counts"]["VISIBLE"], 0.8 * H * W)
        self.assertEqual(r["occ0"].shape, (H // 2, W // 2))
        self.assertEqual(r["bin_edges_m"].shape, (65,))
        # A list of lists (float64) is a valid depth map; so are differently sized frames.
        occgt.pair_ground_truth(**{**good(), "depth0": np.full((H, W), 2.0).tolist()})
        K_small = np.array([[25.0, 0, 15.5], [0, 25.0, 11.5], [0, 0, 1]])
        r = occgt.pair_ground_truth(**{**good(), "depth1": np.full((24, 32), 2.0), "K1": K_small})
        self.assertEqual(r["label10"].shape, (24, 32))

    def test_depth(self) -> None:
        self.check(r"^depth0: .*float32 or float64.*got dtype int32",
                   depth0=np.full((H, W), 2, np.int32))
        self.check(r"^depth1: .*float32 or float64.*got dtype complex64",
                   depth1=np.full((H, W), 2, np.complex64))
        self.check(r"^depth0: .*float32 or float64.*float16", depth0=np.ones((H, W), np.float16))
        self.check(r"^depth0: .*dtype bool", depth0=np.ones((H, W), bool))
        self.check(r"^depth0: .*dtype object", depth0=None)
        self.check(r"^depth0: .*dtype <U", depth0="depth.png")
        self.check(r"^depth0: .*shape \(H, W\), got shape \(48, 64, 1\)",
                   depth0=np.ones((H, W, 1), np.float32))
        self.check(r"^depth1: .*shape \(H, W\), got shape \(3072,\)",
                   depth1=np.ones(H * W, np.float32))
        self.check(r"^depth0: expected width and height in 2\.\.8192", depth0=np.ones((1, 1)))
        self.check(r"^depth0: expected width and height", depth0=np.ones((0, 5), np.float32))
        self.check(r"^depth1: expected width and height", depth1=np.ones((2, 9000), np.float32))
        # A depth map smaller than one patch cell: an error of the patch options.
        self.check(r"stride|cell", depth0=np.ones((4, 4), np.float32),
                   K0=np.array([[5.0, 0, 1.5], [0, 5.0, 1.5], [0, 0, 1]]))

    def test_K(self) -> None:
        K = good()["K0"]
        self.check(r"^K0: expected shape \(3, 3\)", K0=np.zeros((3, 4)))
        self.check(r"^K1: expected shape \(3, 3\)", K1=K[:2])
        self.check(r"^K0: focal lengths must be > 0, got fx=0", K0=np.diag([0.0, 50.0, 1.0]))
        bad = K.copy()
        bad[1, 1] = -50
        self.check(r"^K1: focal lengths must be > 0", K1=bad)
        bad = K.copy()
        bad[0, 2] = np.nan
        self.check(r"^K0: K must be finite", K0=bad)
        bad = K.copy()
        bad[0, 0] = np.inf
        self.check(r"^K1: K must be finite", K1=bad)
        bad = K.copy()
        bad[2, 2] = 2
        self.check(r"^K0: expected \[\[fx, 0, cx\], \[0, fy, cy\], \[0, 0, 1\]\]", K0=bad)
        bad = K.copy()
        bad[0, 1] = 0.5
        self.check(r"^K0: .*no skew", K0=bad)
        self.check(r"^K0: expected a float array .*got dtype complex128", K0=K.astype(complex))
        self.check(r"^K1: expected a float array .*got dtype bool", K1=np.eye(3, dtype=bool))
        self.check(r"^K0: expected a float array", K0="K")

    def test_pose(self) -> None:
        bad = np.eye(4)
        bad[0, 3] = -np.inf
        self.check(r"^world_from_cam0: non-finite pose entries", world_from_cam0=bad)
        bad = np.eye(4)
        bad[1, 1] = np.nan
        self.check(r"^world_from_cam1: non-finite", world_from_cam1=bad)
        self.check(r"^world_from_cam1: rotation is not orthonormal",
                   world_from_cam1=np.diag([2.0, 2.0, 2.0, 1.0]))
        sheared = np.eye(4)
        sheared[0, 1] = 0.01
        self.check(r"^world_from_cam0: rotation is not orthonormal", world_from_cam0=sheared)
        self.check(r"^world_from_cam0: rotation has det < 0",
                   world_from_cam0=np.diag([1.0, 1.0, -1.0, 1.0]))
        bad = np.eye(4)
        bad[3, 0] = 1
        self.check(r"^world_from_cam1: last row of the pose is not \[0 0 0 1\]",
                   world_from_cam1=bad)
        self.check(r"^world_from_cam0: expected shape \(4, 4\)", world_from_cam0=np.eye(4)[:3])
        self.check(r"^world_from_cam1: expected a float array", world_from_cam1=np.eye(4) * 1j)
        # Within the tolerance (1e-3): accepted, as a float32 pose of a dataset would be.
        near = rot_z(0.3).astype(np.float32)
        near[0, 1] += 5e-4
        occgt.pair_ground_truth(**{**good(), "world_from_cam0": near})
        # A camera centre outside the fused map's key range (2^15 voxels per half axis): the
        # voxel size cannot hold it (docs/OCCUPANCY.md, "key range").
        far = np.eye(4)
        far[0, 3] = 1e5
        with self.assertRaisesRegex(ValueError, r"^voxel_m: 0\.05 m holds \+-1\.64e\+03 m .*"
                                    r"frame 1's camera at \(1e\+05, 0, 0\) .*use voxel_m >= 3\.06$"):
            occgt.pair_ground_truth(**{**good(), "world_from_cam1": far}, occupancy=True)

    def test_voxel_too_small_for_the_range(self) -> None:
        """voxel_m=1e-6 holds +-0.0328 m around the origin: every point 2 m away would be
        dropped (an empty volume). Refused, naming the smallest voxel size that works, which
        is then accepted."""
        with self.assertRaisesRegex(
                ValueError, r"^voxel_m: 1e-06 m holds \+-0\.0328 m around the world origin .*"
                r"camera at \(0, 0, 0\) with max_range_m 10 needs \+-10 m: "
                r"use voxel_m >= 0\.000306$"):
            occgt.pair_ground_truth(**good(), occupancy=True, voxel_m=1e-6)
        with self.assertRaisesRegex(ValueError, r"^voxel_m: .*max_range_m 3 needs \+-3 m: "
                                    r"use voxel_m >= 9\.16e-05$"):
            occgt.pair_ground_truth(**good(), occupancy=True, voxel_m=9e-5, max_range_m=3.0)
        # No occupancy: the voxel size is not used.
        occgt.pair_ground_truth(**good(), voxel_m=1e-6)
        # At the smallest size for a 2.5 m range, the wall is fused with nothing dropped (a
        # small frame: rays of 0.1 mm voxels are long).
        small = np.full((4, 4), 0.5, np.float32)
        K = np.array([[4.0, 0, 1.5], [0, 4.0, 1.5], [0, 0, 1]])
        r = occgt.pair_ground_truth(small, small, K, K, np.eye(4), np.eye(4), stride=4,
                                    occupancy=True, voxel_m=7.63e-05, max_range_m=2.5, far_m=2.5)
        self.assertEqual(r["fusion_stats"]["out_of_key_range"], 0)
        self.assertEqual(r["fusion_stats"]["inserted_points"], 32)
        self.assertGreater(int(np.count_nonzero(r["occ0"])), 0)

    def test_fusion_stats(self) -> None:
        """Every pixel of the fused frames is counted: invalid, out of the key range or
        inserted; invalid pixels are those outside the depth range."""
        args = good()
        depth1 = args["depth1"].copy()
        depth1[::3, ::5] = np.nan
        depth1[1, 1] = 0.0
        args["depth1"] = depth1
        invalid = int(np.count_nonzero(~(depth1 > 0)))
        r = occgt.pair_ground_truth(**args, occupancy=True)
        st = r["fusion_stats"]
        self.assertEqual(set(st), {"frames", "pixels", "invalid_pixels", "out_of_key_range",
                                   "after_downsample", "downsample_fallbacks",
                                   "outliers_removed", "inserted_points"})
        self.assertEqual(st["frames"], 2)
        self.assertEqual(st["pixels"], 2 * H * W)
        self.assertEqual(st["invalid_pixels"], invalid)
        self.assertEqual(st["out_of_key_range"], 0)
        self.assertEqual(st["inserted_points"], 2 * H * W - invalid)
        self.assertEqual(st["after_downsample"], st["inserted_points"])
        # A depth range drops more, and says so.
        st = occgt.pair_ground_truth(**args, occupancy=True, max_depth_m=1.5)["fusion_stats"]
        self.assertEqual(st["invalid_pixels"], 2 * H * W)
        self.assertEqual(st["inserted_points"], 0)
        # two_point fuses nothing: None; no occupancy: no key.
        r = occgt.pair_ground_truth(**args, occupancy=True, occupancy_mode="two_point")
        self.assertIsNone(r["fusion_stats"])
        self.assertNotIn("fusion_stats", occgt.pair_ground_truth(**args))

    def test_options(self) -> None:
        self.check(r"^preset: expected one of default, occ2net", preset="occ2")
        self.check(r"^anchor: expected one of center, corner, got 'middle'", anchor="middle")
        self.check(r"^relative_to: expected one of", relative_to="z")
        self.check(r"^bounds: expected one of", bounds="inside")
        self.check(r"^target_lookup: expected one of", target_lookup="round")
        self.check(r"^missing_target: expected one of", missing_target="zero")
        self.check(r"^spacing: expected linear, log or inverse", spacing="exp", occupancy=True)
        self.check(r"^traversal: expected exact or center", traversal="dda", occupancy=True)
        self.check(r"^occupancy_mode: expected octomap or two_point", occupancy_mode="x",
                   occupancy=True)
        self.check(r"abs_tol_m must be finite and >= 0", abs_tol_m=-0.1)
        self.check(r"rel_tol must be finite and >= 0", rel_tol=float("nan"))
        self.check(r"min_depth_m must be finite", min_depth_m=-1.0)
        self.check(r"max_depth_m must be > min_depth_m", min_depth_m=5.0, max_depth_m=1.0)
        self.check(r"stride", stride=0)
        self.check(r"^stride: stride 1000 is larger than the %dx%d depth map \(one patch cell "
                   r"must fit\)$" % (W, H), stride=1000)
        self.check(r"num_bins must be in 1\.\.64", bins=65, occupancy=True)
        self.check(r"num_bins must be in 1\.\.64", bins=0, occupancy=True)
        self.check(r"far_m must be finite and > near_m", near_m=5.0, far_m=1.0, occupancy=True)
        self.check(r"near_m must be finite and > 0", near_m=0.0, occupancy=True)
        self.check(r"near_m must be finite and > 0", near_m=float("inf"), occupancy=True)
        self.check(r"voxel_m must be > 0", voxel_m=0.0, occupancy=True)
        self.check(r"max_range_m must be finite", max_range_m=float("inf"), occupancy=True)
        # A masked array's mask would be dropped by numpy.asarray (masked pixels valid).
        masked = np.ma.masked_less(good()["depth0"], 10.0)
        self.check(r"^depth0: a masked array \(numpy\.ma\) would lose its mask: pass "
                   r"depth\.filled\(0\)", depth0=masked)
        # far_m is the ray range when max_range_m is not given: the message says so.
        self.check(r"max_range_m must be finite.* \(max_range_m is far_m when not given: "
                   r"far_m=nan\)$", far_m=float("nan"), occupancy=True)
        # A wrong Python type is pybind11's TypeError (not a crash either).
        with self.assertRaises(TypeError):
            occgt.pair_ground_truth(**good(), stride="8")  # type: ignore[arg-type]
        # A bool is not a number, and a number is not a bool (abs_tol_m=True was 1.0 m,
        # mutual=0 was False).
        for kwargs, pattern in [
                ({"abs_tol_m": True}, r"^abs_tol_m: expected a number, got bool$"),
                ({"voxel_m": True, "occupancy": True}, r"^voxel_m: expected a number, got bool$"),
                ({"min_depth_m": np.True_}, r"^min_depth_m: expected a number, got bool_$"),
                ({"mutual": 0}, r"^mutual: expected a bool, got int$"),
                ({"occupancy": 1}, r"^occupancy: expected a bool, got int$")]:
            with self.subTest(kwargs=kwargs), self.assertRaisesRegex(TypeError, pattern):
                occgt.pair_ground_truth(**good(), **kwargs)
            with self.subTest(kwargs=kwargs), self.assertRaisesRegex(TypeError, pattern):
                occgt.pair_options(**kwargs)
        self.assertTrue(occgt.pair_ground_truth(**good(), mutual=np.bool_(False),
                                                abs_tol_m=np.float32(0.05))["options"])

    def test_readers(self) -> None:
        with self.assertRaisesRegex(ValueError, r"^format: unknown format .colmap., expected one of"):
            occgt.open_dataset("/nonexistent", "colmap")
        with self.assertRaisesRegex(ValueError, "nonexistent"):
            occgt.open_dataset("/nonexistent", "sevenscenes").scenes()
        root = common.shared("sevenscenes")
        ds = occgt.open_dataset(root, "sevenscenes")
        with self.assertRaises(ValueError):
            ds.scene("no-such-scene")
        scene = ds.scene(ds.scenes()[0])
        with self.assertRaisesRegex(ValueError, r"^frame_id: no frame with id '999999'"):
            scene.load("999999")
        with self.assertRaisesRegex(ValueError, r"^width, height: expected width and height"):
            scene.load(scene.frames[0].id, width=1, height=480)
        with self.assertRaisesRegex(ValueError, r"^width, height:"):
            scene.load(scene.frames[0].id, width=640, height=100000)

    def test_unusable_frame(self) -> None:
        """A frame the reader marks unusable (a non-rigid pose) cannot be loaded."""
        root = common.synth_dataset("synth_badpose", frames=3, resolution="64x48")
        manifest = os.path.join(root, "synth_000", "scene.json")
        with open(manifest) as f:
            doc = json.load(f)
        pose = doc["frames"][1]["world_from_cam"]
        doc["frames"][1]["world_from_cam"] = [[2 * v for v in row[:3]] + row[3:] for row in pose[:3]] \
            + pose[3:]
        with open(manifest, "w") as f:
            json.dump(doc, f)
        scene = occgt.open_dataset(root, "generic").scene("synth_000")
        bad = scene.frames[1]
        self.assertFalse(bad.usable)
        self.assertEqual(bad.reason, "pose: rotation is not orthonormal (|R^T R - I| > 0.001)")
        # Where: the manifest and the JSON field path of a row (all three rows are scaled alike).
        self.assertRegex(bad.detail, "^" + re.escape(manifest) + r": frames\[1\]\.world_from_cam"
                         r"\[[0-2]\]: rotation is not orthonormal \(\|R\^T R - I\| = 3 > 0\.001\)$")
        self.assertEqual(scene.frames[0].detail, "")
        with self.assertRaisesRegex(ValueError, r"^frame_id: frame .* is unusable: pose: rotation "
                                    r"is not orthonormal .*; .*scene\.json: frames\[1\]"):
            scene.load(bad.id)

    def test_python_types_name_the_argument(self) -> None:
        """A wrong Python type is a TypeError naming the argument (not pybind11's list of
        signatures with the arrays' repr); an int beyond the C++ type a ValueError naming it;
        bool is not an int."""
        args = good()
        for kwargs, error, pattern in [
                ({"preset": None}, TypeError, r"^preset: expected a str, got NoneType$"),
                ({"stride": 2**31}, ValueError,
                 r"^stride: expected an int in -2147483648\.\.2147483647, got 2147483648$"),
                ({"stride": True}, TypeError, r"^stride: expected an int, got bool$"),
                ({"stride": 8.0}, TypeError, r"^stride: expected an int, got float$"),
                ({"anchor": 1}, TypeError, r"^anchor: expected a str, got int$")]:
            with self.subTest(kwargs=kwargs), self.assertRaisesRegex(error, pattern):
                occgt.pair_ground_truth(**args, **kwargs)
        with self.assertRaisesRegex(TypeError, r"^preset: expected a str, got int$"):
            occgt.pair_options(3)  # type: ignore[arg-type]
        self.assertEqual(occgt.pair_options(stride=np.int64(4))["patch_options"]["stride"], 4)
        views = ([args["depth0"]] * 2, [args["K0"]] * 2, [args["world_from_cam0"]] * 2)
        for kwargs, error, pattern in [
                ({"seed": -1}, ValueError,
                 r"^seed: expected an int in 0\.\.18446744073709551615, got -1$"),
                ({"seed": 1.5}, TypeError, r"^seed: expected an int, got float$"),
                ({"num_tracks": 2**40}, ValueError, r"^num_tracks: expected an int in "),
                ({"query_view": "0"}, TypeError, r"^query_view: expected an int, got str$"),
                ({"preset": None}, TypeError, r"^preset: expected a str, got NoneType$")]:
            with self.subTest(kwargs=kwargs), self.assertRaisesRegex(error, pattern):
                occgt.views_ground_truth(*views, **kwargs)
        self.assertEqual(occgt.views_ground_truth(*views, num_tracks=np.int32(3),
                                                  seed=np.uint64(2**63))["queries"].shape, (3, 2))
        root = common.synth_dataset("badinput_types", frames=2, resolution="64x48")
        with self.assertRaisesRegex(TypeError, r"^root: expected a path \(str or os.PathLike\), "
                                    r"got NoneType$"):
            occgt.open_dataset(None, "generic")  # type: ignore[arg-type]
        with self.assertRaisesRegex(ValueError, r"^device: unknown device 'phone'"):
            occgt.open_dataset(root, "scannetpp", device="phone")
        dataset = occgt.open_dataset(root, "generic")
        with self.assertRaisesRegex(TypeError, r"^name: expected a str, got NoneType$"):
            dataset.scene(None)  # type: ignore[arg-type]
        scene = dataset.scene(dataset.scenes()[0])
        frame = scene.frames[0].id
        for call, error, pattern in [
                (lambda: scene.load(0), TypeError, r"^frame_id: expected a str, got int$"),
                (lambda: scene.load(frame, 64.0, 48), TypeError, r"^width: expected an int, got float$"),
                (lambda: scene.load(frame, 64, "48"), TypeError, r"^height: expected an int, got str$"),
                (lambda: scene.load(frame, 2**31, 48), ValueError, r"^width: expected an int in "),
                (lambda: scene.load_color(None), TypeError, r"^frame_id: expected a str"),
                (lambda: scene.load_color(frame, 64, 1.5), TypeError, r"^height: expected an int"),
                (lambda: scene.fuse(frame, 1), TypeError, r"^id1: expected a str, got int$"),
                (lambda: scene.fuse(frame, frame, scope=None), TypeError, r"^scope: expected a str"),
                (lambda: occgt.pair_from_scene(None, frame, frame),  # type: ignore[arg-type]
                 TypeError, r"^scene: expected an occgt.Scene \(Dataset.scene\), got NoneType$"),
                (lambda: occgt.pair_from_scene(scene, frame, frame, scope=None),  # type: ignore
                 TypeError, r"^scope: expected a str, got NoneType$")]:
            with self.subTest(pattern=pattern), self.assertRaisesRegex(error, pattern):
                call()
        depth, _, _ = scene.load(frame, np.int64(64), np.int32(48))
        self.assertEqual(depth.shape, (48, 64))
        # Fusion's numbers, render_depth's and depth_at_image_size's arguments.
        for call, error, pattern in [
                (lambda: scene.fuse(frame, frame, voxel_m="0.05"), TypeError,
                 r"^voxel_m: expected a number, got str$"),
                (lambda: scene.fuse(frame, frame, far_m=True), TypeError,
                 r"^far_m: expected a number, got bool$"),
                (lambda: scene.fuse(frame, frame, dataset_max_depth_m=[1.0]), TypeError,
                 r"^dataset_max_depth_m: expected a number, got list$"),
                (lambda: scene.fuse(frame, frame, max_range_m=np.array([1.0, 2.0])), TypeError,
                 r"^max_range_m: expected a number, got ndarray$")]:
            with self.subTest(pattern=pattern), self.assertRaisesRegex(error, pattern):
                call()
        self.assertEqual(scene.fuse(frame, frame, voxel_m=np.float32(0.1), far_m=5).scope, "pair")
        mesh = occgt.load_mesh(common.shared("meshes/sevenscenes-rgbd-frames-tsdf.ply"))
        K = np.array([[50.0, 0, 31.5], [0, 50.0, 23.5], [0, 0, 1]])
        for call, error, pattern in [
                (lambda: occgt.load_mesh(3), TypeError,  # type: ignore[arg-type]
                 r"^path: expected a path \(str or os.PathLike\), got int$"),
                (lambda: occgt.render_depth("mesh.ply", K, np.eye(4), 64, 48), TypeError,
                 r"^mesh: expected an occgt.Mesh \(occgt.load_mesh\), got str$"),
                (lambda: occgt.render_depth(mesh, K, np.eye(4), "64", 48), TypeError,
                 r"^width: expected an int, got str$"),
                (lambda: occgt.render_depth(mesh, K, np.eye(4), 64, 48.0), TypeError,
                 r"^height: expected an int, got float$"),
                (lambda: occgt.render_depth(mesh, K, np.eye(4), 64, 48, model=0), TypeError,
                 r"^model: expected a str, got int$"),
                (lambda: occgt.render_depth(mesh, K, np.eye(4), 64, 48, near_m="0.1"), TypeError,
                 r"^near_m: expected a number, got str$"),
                (lambda: occgt.depth_at_image_size(np.ones((8, 8), np.float32), K, "2", 4, 4),
                 ValueError, r"^scale: expected \(sx, sy\), two numbers, got '2'$"),
                (lambda: occgt.depth_at_image_size(np.ones((8, 8), np.float32), K, (2, 2, 2), 4,
                                                   4),
                 ValueError, r"^scale: expected \(sx, sy\), two numbers, got \(2, 2, 2\)$"),
                (lambda: occgt.depth_at_image_size(np.ones((8, 8), np.float32), K, (2, 2), 4.0,
                                                   4),
                 TypeError, r"^width: expected an int, got float$")]:
            with self.subTest(pattern=pattern), self.assertRaisesRegex(error, pattern):
                call()
        # LoFTR's scale0 is a tensor or an array; numpy scalars are numbers.
        d, _ = occgt.depth_at_image_size(np.ones((8, 8), np.float32), K, np.array([2.0, 2.0]),
                                         4, 4)
        self.assertEqual(d.shape, (4, 4))
        self.assertEqual(occgt.render_depth(mesh, K, np.eye(4), np.int64(64), 48,
                                            near_m=np.float64(0.1), far_m=10).shape, (48, 64))

    def test_torch_tensors_and_array_likes(self) -> None:
        """CPU tensors are inputs; one numpy cannot read says why (numpy's reason)."""
        import torch

        args = good()
        want = occgt.pair_ground_truth(**args)["label01"]
        got = occgt.pair_ground_truth(**{**args, "depth0": torch.from_numpy(args["depth0"]),
                                         "K0": torch.from_numpy(args["K0"])})["label01"]
        self.assertTrue(np.array_equal(got, want))
        grad = torch.from_numpy(args["depth0"]).requires_grad_()
        with self.assertRaisesRegex(ValueError, r"^depth0: expected a NumPy array or array-like .*"
                                    r"got Tensor \(numpy.asarray: .*requires grad"):
            occgt.pair_ground_truth(**{**args, "depth0": grad})
        with self.assertRaisesRegex(ValueError, r"^K1: .*got list \(numpy.asarray: .*inhomogeneous"):
            occgt.pair_ground_truth(**{**args, "K1": [[50.0, 0, 31.5], [0, 50.0]]})
        # Non-finite K: said as such, not as a skewed K.
        with self.assertRaisesRegex(ValueError, r"^K1: K must be finite, got \[\[nan, nan"):
            occgt.pair_ground_truth(**{**args, "K1": args["K1"] * np.nan})
        # views_ground_truth: a generator or None names its type, not "shape ()"; a uint64
        # query beyond int64 is shown as given, not wrapped.
        d, K, T = args["depth0"], args["K0"], args["world_from_cam0"]
        with self.assertRaisesRegex(ValueError, r"^depths: expected a list of arrays or one "
                                    r"array of 3 dimensions, got generator$"):
            occgt.views_ground_truth((x for x in [d, d]), [K, K], [T, T])
        with self.assertRaisesRegex(ValueError, r"^Ks: .*got NoneType$"):
            occgt.views_ground_truth([d], None, [T])  # type: ignore[arg-type]
        with self.assertRaisesRegex(ValueError, r"^queries: expected pixels \(u, v\) inside the "
                                    r"64x48 image, got 9223372036854775813 at row 0$"):
            occgt.views_ground_truth([d, d], [K, K], [T, T],
                                     queries=np.array([[2**63 + 5, 0]], np.uint64))

    def test_scene_load_names_the_unreadable_file(self) -> None:
        """An unreadable depth file or mesh: the ValueError names the file (it said
        "depth_source: ..." without it)."""
        root = common.synth_dataset("badinput_files", frames=3, resolution="64x48")
        scene = occgt.open_dataset(root, "generic").scene("synth_000")
        frame = scene.frames[1]
        with open(frame.depth_path, "wb") as f:
            f.write(b"garbage")
        with self.assertRaisesRegex(ValueError, "^" + re.escape(frame.depth_path) +
                                    r": not a \.npy file"):
            scene.load(frame.id, 64, 48)
        os.remove(frame.depth_path)
        with self.assertRaisesRegex(ValueError, "^" + re.escape(frame.depth_path) +
                                    r": cannot open file"):
            scene.load(frame.id, 64, 48)
        missing = os.path.join(root, "no-mesh.ply")
        with self.assertRaisesRegex(TypeError, r"^mesh_path: expected a path \(str or "
                                    r"os\.PathLike\), got int$"):
            scene.mesh_path = 3  # type: ignore[assignment]
        scene.mesh_path = pathlib.Path(missing)  # type: ignore[assignment]
        self.assertEqual(scene.mesh_path, missing)
        scene.mesh_path = missing
        with self.assertRaisesRegex(ValueError, "^" + re.escape(missing) + r": cannot open file"):
            scene.load(scene.frames[0].id, 64, 48, depth_source="mesh")

    def test_dense_volume(self) -> None:
        words = np.zeros((4, 5), np.uint64)
        with self.assertRaisesRegex(ValueError, r"^occ: expected dtype uint64 or int64"):
            occgt.dense_volume(words.astype(np.int32), words)
        with self.assertRaisesRegex(ValueError, r"^known: expected dtype uint64 or int64"):
            occgt.dense_volume(words, words.astype(np.float64))
        # int64 is the same bits (occgt.torch's words: torch has no uint64), bit 63 included.
        bits = np.array([[1 << 63, 5, 0], [2, 1 << 40, 3]], np.uint64)
        known = np.full_like(bits, np.uint64(2**64 - 1))
        self.assertTrue(np.array_equal(occgt.dense_volume(bits.view(np.int64), known.view(np.int64)),
                                       occgt.dense_volume(bits, known)))
        # A bit at or past bins is of another bin count (it was ignored).
        with self.assertRaisesRegex(ValueError, r"^occ: element 0 has a bit at or past bins=8 "):
            occgt.dense_volume(bits, known, bins=8)
        with self.assertRaisesRegex(ValueError, r"^known: element 0 has a bit at or past bins=2 "):
            occgt.dense_volume(np.zeros_like(bits), known, bins=2)
        with self.assertRaisesRegex(ValueError, r"^occ: expected shape \(H/2, W/2\)"):
            occgt.dense_volume(words.ravel(), words)
        with self.assertRaisesRegex(ValueError, r"^known: expected the shape of occ \(4, 5\)"):
            occgt.dense_volume(words, words[:3])
        with self.assertRaisesRegex(ValueError, r"^bins: num_bins must be in 1\.\.64"):
            occgt.dense_volume(words, words, bins=0)
        self.assertEqual(occgt.dense_volume(words, words, 2).shape, (2, 4, 5))


if __name__ == "__main__":
    unittest.main(verbosity=2)
