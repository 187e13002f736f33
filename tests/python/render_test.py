"""occgt.load_mesh / occgt.render_depth: a fronto-parallel and a tilted plane against their
closed-form depth in the three camera models, the shared TSDF mesh at the 7-Scenes sample's
poses against the sensor depth it was fused from (../shared/data, required), one Mesh shared by
threads (the serial results), and ValueError for every bad argument and bad file."""
from __future__ import annotations

import concurrent.futures
import os
import sys
import unittest

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
import common  # noqa: E402

import occgt  # noqa: E402

TSDF = "meshes/sevenscenes-rgbd-frames-tsdf.ply"


def write_plane_ply(path: str, z: float, half: float = 100.0) -> None:
    """An ASCII PLY of the square |x|, |y| <= half at height z (two triangles)."""
    with open(path, "w") as f:
        f.write("ply\nformat ascii 1.0\nelement vertex 4\nproperty double x\nproperty double y\n"
                "property double z\nelement face 2\nproperty list uchar int vertex_indices\n"
                "end_header\n")
        for x, y in ((-half, -half), (half, -half), (half, half), (-half, half)):
            f.write(f"{x} {y} {z}\n")
        f.write("3 0 1 2\n3 0 2 3\n")


class Planes(unittest.TestCase):
    @classmethod
    def setUpClass(cls) -> None:
        cls.dir = common.scratch("render_planes")
        cls.path = os.path.join(cls.dir, "plane.ply")
        write_plane_ply(cls.path, 2.0)
        cls.mesh = occgt.load_mesh(cls.path)
        cls.K = np.array([[30.0, 0.0, 39.5], [0.0, 31.0, 29.5], [0.0, 0.0, 1.0]])

    def test_mesh(self) -> None:
        self.assertEqual((self.mesh.num_vertices, self.mesh.num_triangles), (4, 2))
        self.assertEqual(self.mesh.path, self.path)

    def test_fronto_parallel_every_model(self) -> None:
        # The plane z = 2 m: planar depth 2 along every ray, whatever its direction.
        for model, dist in (("pinhole", None), ("opencv", [-0.2, 0.03, 0.001, 0.002, 0.0]),
                            ("opencv", [-0.2, 0.03, 0.001, 0.002]),
                            ("opencv_fisheye", [0.02, -0.01, 0.003, -0.0005])):
            with self.subTest(model=model, dist=dist):
                depth = occgt.render_depth(self.mesh, self.K, np.eye(4), 80, 60, model=model,
                                           dist=dist)
                self.assertEqual((depth.dtype, depth.shape), (np.float32, (60, 80)))
                hit = depth > 0
                self.assertGreater(hit.mean(), 0.9)
                np.testing.assert_allclose(depth[hit], 2.0, atol=1e-4)

    def test_tilted_pinhole_closed_form(self) -> None:
        a = 0.3  # camera turned about its x axis, 0.5 m above the origin
        pose = np.eye(4)
        pose[:3, :3] = [[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]]
        pose[2, 3] = 0.5
        depth = occgt.render_depth(self.mesh, self.K, pose, 80, 60)
        u, v = np.meshgrid(np.arange(80.0), np.arange(60.0))
        rays = np.stack([(u - 39.5) / 30.0, (v - 29.5) / 31.0, np.ones_like(u)], -1)
        dz = rays @ pose[2, :3]  # world z of the ray per unit of camera z
        expected = np.where(dz > 0, (2.0 - 0.5) / np.where(dz > 0, dz, 1), 0.0)
        expected[expected > 20.0] = 0.0
        np.testing.assert_allclose(depth, expected, atol=1e-4)
        self.assertGreater(float((depth > 0).mean()), 0.5)
        # near_m / far_m
        self.assertTrue(np.all(occgt.render_depth(self.mesh, self.K, pose, 80, 60, far_m=1.0) == 0))
        near = occgt.render_depth(self.mesh, self.K, pose, 80, 60, near_m=1.6)
        np.testing.assert_array_equal(near, np.where(expected >= 1.6, depth, 0))

    def test_bad_arguments(self) -> None:
        K, mesh = self.K, self.mesh
        bad = [
            (dict(model="kannala"), "model"),
            (dict(model="pinhole", dist=[0.1, 0, 0, 0]), "dist"),
            (dict(model="opencv_fisheye"), "dist"),
            (dict(model="opencv_fisheye", dist=[0.1, 0, 0, 0, 0.2]), "dist"),
            (dict(model="opencv", dist=[0.1, 0]), "dist"),
            (dict(model="opencv", dist=[np.nan, 0, 0, 0]), "dist"),
            (dict(near_m=2.0, far_m=1.0), "near_m"),
            (dict(near_m=-1.0), "near_m"),
        ]
        for kwargs, name in bad:
            with self.subTest(kwargs=kwargs):
                with self.assertRaisesRegex(ValueError, "^" + name):
                    occgt.render_depth(mesh, K, np.eye(4), 80, 60, **kwargs)  # type: ignore[arg-type]
        with self.assertRaisesRegex(ValueError, "^K"):
            occgt.render_depth(mesh, np.eye(2), np.eye(4), 80, 60)
        with self.assertRaisesRegex(ValueError, "^world_from_cam"):
            occgt.render_depth(mesh, K, np.full((4, 4), np.nan), 80, 60)
        with self.assertRaisesRegex(ValueError, "^width"):
            occgt.render_depth(mesh, K, np.eye(4), 0, 60)
        with self.assertRaises(TypeError):
            occgt.render_depth("mesh.ply", K, np.eye(4), 80, 60)  # type: ignore[arg-type]

    def test_bad_files(self) -> None:
        with self.assertRaisesRegex(ValueError, "nonexistent.ply"):
            occgt.load_mesh(os.path.join(self.dir, "nonexistent.ply"))
        with open(self.path, "rb") as f:
            good = f.read()
        truncated = os.path.join(self.dir, "truncated.ply")
        with open(truncated, "wb") as f:
            f.write(good[:-8])
        with self.assertRaisesRegex(ValueError, "truncated.ply: .*(ends early|claims)"):
            occgt.load_mesh(truncated)
        huge = os.path.join(self.dir, "huge.ply")
        with open(huge, "wb") as f:
            f.write(good.replace(b"element face 2", b"element face 900000000000"))
        with self.assertRaisesRegex(ValueError, "huge.ply: element face claims"):
            occgt.load_mesh(huge)


class SevenScenes(unittest.TestCase):
    @classmethod
    def setUpClass(cls) -> None:
        cls.mesh = occgt.load_mesh(common.shared(TSDF))
        dataset = occgt.open_dataset(common.shared("sevenscenes"), "sevenscenes")
        cls.scene = dataset.scene("rgbd-frames")

    def render(self, frame: occgt.Frame) -> np.ndarray:
        return occgt.render_depth(self.mesh, frame.K, frame.world_from_cam, frame.width,
                                  frame.height)

    def test_matches_sensor_depth(self) -> None:
        diffs = []
        for frame in self.scene.frames[::7]:
            sensor, _, _ = self.scene.load(frame.id)
            rendered = self.render(frame)
            both = (sensor > 0) & (rendered > 0)
            self.assertGreater(both.sum() / max(1, (sensor > 0).sum()), 0.9)
            diffs.append(np.abs(sensor[both] - rendered[both]))
        median = float(np.median(np.concatenate(diffs)))
        self.assertLess(median, 0.01)

    def test_scene_load_depth_source(self) -> None:
        dataset = occgt.open_dataset(common.shared("sevenscenes"), "sevenscenes")
        scene = dataset.scene("rgbd-frames")
        self.assertEqual(scene.mesh_path, "")
        with self.assertRaisesRegex(ValueError, "needs a mesh"):
            scene.load("000150", depth_source="mesh")
        with self.assertRaisesRegex(ValueError, "^depth_source"):
            scene.load("000150", depth_source="lidar")
        scene.mesh_path = self.mesh.path
        sensor, K, pose = scene.load("000150")
        np.testing.assert_array_equal(sensor, scene.load("000150", depth_source="sensor")[0])
        for width, height in ((640, 480), (320, 240)):
            sensor, K, pose = scene.load("000150", width, height)
            mesh, K2, _ = scene.load("000150", width, height, depth_source="mesh")
            np.testing.assert_array_equal(K, K2)
            np.testing.assert_array_equal(mesh, occgt.render_depth(self.mesh, K, pose, width, height))
            # fused, by the rule of docs/GROUND_TRUTH.md "Depth sources" (7-Scenes: 0.1-10 m)
            fused, _, _ = scene.load("000150", width, height, depth_source="fused")
            has_s = (sensor >= 0.1) & (sensor <= 10.0)
            has_m = mesh > 0
            agree = np.abs(sensor.astype(np.float64) - mesh) <= 0.2 + 0.01 * mesh.astype(np.float64)
            expected = np.where(has_s & ~has_m, sensor, 0)
            expected = np.where(~has_s & has_m, mesh, expected)
            expected = np.where(has_s & has_m & agree, sensor, expected)
            np.testing.assert_array_equal(fused, expected.astype(np.float32))
            self.assertGreater(int((fused > 0).sum()), int((sensor > 0).sum()))
        # pair_from_scene with a depth source: fewer pixels without depth.
        plain = occgt.pair_from_scene(scene, "000150", "000160")
        fused_pair = occgt.pair_from_scene(scene, "000150", "000160", depth_source="fused")
        self.assertLess(int((fused_pair["label01"] == occgt.NO_DEPTH).sum()),
                        int((plain["label01"] == occgt.NO_DEPTH).sum()))

    def test_threads_share_one_mesh(self) -> None:
        frames = self.scene.frames[::10]
        serial = [self.render(f) for f in frames]
        with concurrent.futures.ThreadPoolExecutor(4) as pool:
            parallel = list(pool.map(self.render, frames + frames))
        for k, depth in enumerate(parallel):
            np.testing.assert_array_equal(depth, serial[k % len(frames)])


if __name__ == "__main__":
    unittest.main(verbosity=2)
