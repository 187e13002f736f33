"""N-view shards of `occgt tuples --shards` (libgt/pipeline/views_write.h, docs/MULTIVIEW.md
"N-view shards"): every sample, read back with tarfile and numpy, holds its tuple's frames as
occgt's readers load them (depth, K, world_from_cam, colour) and ground truth bit for bit equal
to occgt.views_ground_truth of those frames with the recipe's label options and the stated
track seed; its JSON follows schemas/views_sample.schema.json and names the tuple of
tuples.jsonl; `occgt validate` and `occgt merge --verify` check the split against the N-view
schemas; the files are byte-identical with 1 and 2 threads; a re-run skips complete shards and
a removed shard is rewritten with the same bytes."""
from __future__ import annotations

import glob
import json
import os
import shutil
import subprocess
import unittest
from typing import Dict, Tuple

import jsonschema
import numpy as np

import common
import occgt

RECIPE = """name: views-shards-test
split: views
seed: 5
resolution: [96, 72]
dataset:
  format: synthetic
  synthetic: {scenes: 2, frames: 10, width: 96, height: 72, seed: 4}
  frame_stride: 1
  min_valid_depth_fraction: 0.3
labels: {preset: default}
selection:
  max_frame_gap: 0
  pruning: {max_distance_m: 4.0, max_view_angle_deg: 120, frustum: true}
  score_stride: 4
  overlap: [0.0, 1.0]
  visible_overlap: [0.0, 1.0]
  occlusion: [0.0, 1.0]
  quota_per_scene: 0
  views: [3, 5]
  tuples: {edge_threshold: 0.2, pair_covisibility: [0.0, 0.97], restarts: 4, quota_per_scene: 4}
occupancy: {enabled: false}
shards: {samples_per_shard: 3}
sample: {image: png, depth: true, labels: true, occupancy: false}
"""


def file_ids(root: str) -> Dict[str, Tuple[int, int]]:
    """{relative path: (inode, mtime_ns)} of every file under root."""
    out = {}
    for p in glob.glob(os.path.join(root, "**", "*"), recursive=True):
        if os.path.isfile(p):
            st = os.stat(p)
            out[os.path.relpath(p, root)] = (st.st_ino, st.st_mtime_ns)
    return out


def read_tree(root: str) -> Dict[str, bytes]:
    out = {}
    for p in sorted(glob.glob(os.path.join(root, "**", "*"), recursive=True)):
        if os.path.isfile(p):
            out[os.path.relpath(p, root)] = common.read_bytes(p)
    return out


class ViewsShards(unittest.TestCase):
    @classmethod
    def setUpClass(cls) -> None:
        cls.dir = common.scratch("views_shards")
        cls.recipe = os.path.join(cls.dir, "recipe.yaml")
        with open(cls.recipe, "w") as f:
            f.write(RECIPE)
        cls.data = os.path.join(cls.dir, "data")
        cls.out1 = os.path.join(cls.dir, "t1")
        common.occgt("covis", cls.recipe, "--out", cls.out1, "--threads", 1, "--root", cls.data)
        cls.out2 = os.path.join(cls.dir, "t2")
        shutil.copytree(os.path.join(cls.out1, "covisibility"),
                        os.path.join(cls.out2, "covisibility"))
        cls.summary = json.loads(common.occgt("tuples", cls.recipe, "--out", cls.out1, "--shards",
                                              "--threads", 1, "--json", "--root", cls.data).stdout)
        common.occgt("tuples", cls.recipe, "--out", cls.out2, "--shards", "--threads", 2,
                     "--root", cls.data)
        cls.views = os.path.join(cls.out1, "views")
        with open(os.path.join(cls.out1, "tuples.jsonl")) as f:
            cls.lines = [json.loads(x) for x in f]

    def test_one_sample_per_tuple_in_order(self) -> None:
        samples = common.read_shard_samples(self.views)
        self.assertGreaterEqual(len(self.lines), 5)  # spans several shards of 3
        self.assertEqual(len(samples), len(self.lines))
        self.assertEqual(self.summary["shards"]["samples"], len(self.lines))
        self.assertEqual(self.summary["shards"]["shards"], (len(self.lines) + 2) // 3)
        with open(os.path.join(common.SOURCE, "schemas", "views_sample.schema.json")) as f:
            schema = json.load(f)
        with open(os.path.join(common.SOURCE, "schemas", "index.schema.json")) as f:
            with open(os.path.join(self.views, "index.json")) as g:
                jsonschema.validate(json.load(g), json.load(f))
        with open(os.path.join(self.views, "pairs.jsonl")) as f:
            rows = [json.loads(x) for x in f]
        for k, (s, line, row) in enumerate(zip(samples, self.lines, rows)):
            meta = s["json"]
            jsonschema.validate(meta, schema)
            self.assertEqual(meta["tuple_index"], k)
            self.assertEqual(s["__key__"], meta["key"])
            self.assertEqual(row["key"], meta["key"])
            self.assertEqual(row["frame_ids"], line["frame_ids"])
            self.assertEqual(meta["scene"], line["scene"])
            self.assertEqual([f["id"] for f in meta["frames"]], line["frame_ids"])
            np.testing.assert_array_equal(np.float32(meta["covisibility"]),
                                          np.float32(line["covisibility"]))
            self.assertEqual(meta["num_views"], len(line["frame_ids"]))

    def test_other_tuples_are_refused_before_tuples_jsonl_changes(self) -> None:
        """A re-run whose tuples differ (another seed) into a folder with N-view shards is
        refused, with or without --shards, and leaves tuples.jsonl as it was."""
        other = os.path.join(self.dir, "other_seed.yaml")
        with open(other, "w") as f:
            f.write(RECIPE.replace("seed: 5\n", "seed: 6\n", 1))
        path = os.path.join(self.out1, "tuples.jsonl")
        before = common.read_bytes(path)
        for extra in (["--shards"], []):
            r = subprocess.run([common.BINARY, "tuples", other, "--out", self.out1, "--root",
                                self.data, *extra], capture_output=True, text=True)
            self.assertEqual(r.returncode, 1, r.stderr)
            self.assertIn("written for other tuples or options", r.stderr)
            self.assertEqual(len(r.stderr.strip().splitlines()), 1, r.stderr)
            self.assertEqual(common.read_bytes(path), before)

    def test_validate_and_merge_verify(self) -> None:
        """`occgt validate` and `occgt merge --verify` check an N-view split against the
        N-view schemas (views_sample, views_line): valid as written; a line that lacks a
        required key is reported with its line number and schema."""
        with open(os.path.join(common.SOURCE, "schemas", "views_line.schema.json")) as f:
            line_schema = json.load(f)
        with open(os.path.join(self.views, "pairs.jsonl")) as f:
            rows = [json.loads(x) for x in f]
        for row in rows:
            jsonschema.validate(row, line_schema)
        self.assertIn("valid", common.occgt("validate", self.views).stdout)
        # The tuples' folder itself: the index is not found, and the message says where it is.
        r = subprocess.run([common.BINARY, "validate", self.out1], capture_output=True, text=True)
        self.assertEqual(r.returncode, 1, r.stderr)
        self.assertIn(f"(the N-view shards of occgt tuples --shards are in {self.views}: "
                      "validate that folder)", r.stdout)
        copy = os.path.join(self.dir, "views_copy")
        shutil.rmtree(copy, ignore_errors=True)
        shutil.copytree(self.views, copy)
        os.remove(os.path.join(copy, "summary.json"))
        self.assertIn("(verified)", common.occgt("merge", copy, "--verify").stdout)
        # tuples --shards wrote the summary merge writes: the folder is the same either way.
        self.assertEqual(common.read_bytes(os.path.join(self.views, "summary.json")),
                         common.read_bytes(os.path.join(copy, "summary.json")))
        # Its summary counts tuples per scene, under that name, by the summary schema.
        with open(os.path.join(copy, "summary.json")) as f:
            merged = json.load(f)
        with open(os.path.join(common.SOURCE, "schemas", "summary.schema.json")) as f:
            summary_schema = json.load(f)
        jsonschema.validate(merged, summary_schema)
        self.assertNotIn("pairs_per_scene", merged)
        per_scene: Dict[str, int] = {}
        for row in rows:
            per_scene[row["scene"]] = per_scene.get(row["scene"], 0) + 1
        self.assertEqual(merged["tuples_per_scene"], per_scene)
        self.assertEqual(merged["samples"], len(rows))
        del rows[1]["tuple_index"]
        with open(os.path.join(copy, "pairs.jsonl"), "w") as f:
            f.writelines(json.dumps(r) + "\n" for r in rows)
        r = subprocess.run([common.BINARY, "validate", copy], capture_output=True, text=True)
        self.assertEqual(r.returncode, 1, r.stderr)
        self.assertIn("pairs.jsonl:2: views_line.schema.json: <root>: Missing required property "
                      "'tuple_index'", r.stdout)

    def test_bits_equal_views_ground_truth(self) -> None:
        ds = occgt.open_dataset(self.data, "generic")
        checked = 0
        for s in common.read_shard_samples(self.views):
            meta = s["json"]
            scene = ds.scene(meta["scene"])
            n = meta["num_views"]
            frames = [scene.load(f["id"], 96, 72) for f in meta["frames"]]
            for i, (depth, K, pose) in enumerate(frames):
                np.testing.assert_array_equal(s[f"depth{i}"], depth)
                np.testing.assert_array_equal(s[f"image{i}"],
                                              scene.load_color(meta["frames"][i]["id"], 96, 72))
            np.testing.assert_allclose(s["intrinsics"], np.stack([f[1] for f in frames]), rtol=1e-12)
            np.testing.assert_array_equal(s["world_from_cam"], np.stack([f[2] for f in frames]))
            np.testing.assert_allclose(np.array(meta["K"]), s["intrinsics"], rtol=1e-12)
            np.testing.assert_allclose(np.array(meta["world_from_cam"]), s["world_from_cam"],
                                       rtol=1e-12)
            t = meta["tracks"]
            self.assertEqual(t["seed"], 5 + meta["tuple_index"])  # recipe seed + line
            truth = occgt.views_ground_truth(
                [f[0] for f in frames], s["intrinsics"], s["world_from_cam"], preset="default",
                num_tracks=t["num_tracks"], query_view=t["query_view"], seed=t["seed"],
                dataset_depth_range=(scene.min_depth_m, scene.max_depth_m))
            self.assertEqual(truth["label_options"], meta["label_options"])
            for name in ["visible_in", "occluded_in", "valid", "queries", "track_state"]:
                self.assertEqual(s[name].dtype, truth[name].dtype, name)  # type: ignore
                np.testing.assert_array_equal(s[name], truth[name], err_msg=name)  # type: ignore
            for name in ["track_xy", "track_depth"]:
                np.testing.assert_array_equal(s[name], truth[name], err_msg=name)  # type: ignore
            self.assertEqual(s["visible_in"].shape, (n, 72, 96))
            self.assertEqual(t["count"], len(truth["queries"]))
            # The counts: bits of the ordered pairs i != j.
            vis = occ = 0
            for i in range(n):
                for j in range(n):
                    if i != j:
                        vis += int(((s["visible_in"][i] >> j) & 1).sum())
                        occ += int(((s["occluded_in"][i] >> j) & 1).sum())
            m = meta["metrics"]
            self.assertEqual((m["counts"]["VISIBLE"], m["counts"]["OCCLUDED"], m["valid"]),
                             (vis, occ, int(s["valid"].sum())))
            self.assertAlmostEqual(m["occlusion_ratio_visible"], occ / max(vis + occ, 1))
            # The colour camera of this dataset is its depth camera (no colour K in the
            # manifests): image.K equals K; test_colour_camera_K covers another colour K.
            self.assertEqual(meta["image"]["format"], "png")
            np.testing.assert_allclose(np.array(meta["image"]["K"]), s["intrinsics"], rtol=1e-12)
            checked += 1
        self.assertGreaterEqual(checked, 5)
        self.assertGreater(sum(s["json"]["metrics"]["counts"]["OCCLUDED"] for s in common.read_shard_samples(self.views)), 0)

    def test_thread_count_and_resume(self) -> None:
        one = read_tree(self.views)
        self.assertEqual(one, read_tree(os.path.join(self.out2, "views")))
        self.assertTrue(any(p.endswith(".tar") for p in one))
        ids = file_ids(self.out1)
        again = json.loads(common.occgt("tuples", self.recipe, "--out", self.out1, "--shards",
                                        "--json", "--root", self.data).stdout)
        self.assertEqual(again["shards"]["shards_written"], 0)
        self.assertEqual(again["shards"]["shards_skipped"], again["shards"]["shards"])
        self.assertEqual(read_tree(self.views), one)
        # Nothing to do: no file rewritten (tuples.jsonl, the indices, the shards).
        self.assertEqual(file_ids(self.out1), ids)
        os.remove(os.path.join(self.views, "views-000001.tar"))
        os.remove(os.path.join(self.views, "parts", "views-000001.json"))
        third = json.loads(common.occgt("tuples", self.recipe, "--out", self.out1, "--shards",
                                        "--json", "--root", self.data).stdout)
        self.assertEqual(third["shards"]["shards_written"], 1)
        self.assertEqual(read_tree(self.views), one)
        self.assertFalse(glob.glob(os.path.join(self.views, "*.tmp*")))
        # Other options (here the image format) over the complete shards: refused, untouched.
        other = os.path.join(self.dir, "jpg.yaml")
        with open(other, "w") as f:
            f.write(RECIPE.replace("image: png", "image: jpg"))
        r = subprocess.run([common.BINARY, "tuples", other, "--out", self.out1, "--shards",
                            "--root", self.data], capture_output=True, text=True)
        self.assertEqual(r.returncode, 1, r.stderr)
        self.assertIn("written for other tuples or options", r.stderr)
        self.assertEqual(read_tree(self.views), one)

    def test_colour_camera_K(self) -> None:
        """A colour camera other than the depth camera (a manifest's `color.K`): the json's
        image.K holds each view's colour K at W x H, K and intrinsics.npy stay the depth K
        (docs/FORMATS.md "N-view shards"), as a pair sample's image.K0/K1 and K0/K1."""
        data = os.path.join(self.dir, "colour_data")
        shutil.rmtree(data, ignore_errors=True)
        shutil.copytree(self.data, data)
        colour_K: Dict[str, list] = {}
        for manifest in glob.glob(os.path.join(data, "*", "scene.json")):
            with open(manifest) as f:
                m = json.load(f)
            for k, frame in enumerate(m["frames"]):
                K = np.array(frame["K"])
                K[0, 0] *= 1.0 + 0.01 * k  # fx, cx differ from the depth camera's, per frame
                K[0, 2] += 1.5
                frame["color"]["K"] = K.tolist()
                colour_K[m["scene"] + "/" + frame["id"]] = K.tolist()
            with open(manifest, "w") as f:
                json.dump(m, f)
        recipe = os.path.join(self.dir, "generic.yaml")
        with open(recipe, "w") as f:
            f.write(RECIPE.replace(
                "  format: synthetic\n  synthetic: {scenes: 2, frames: 10, width: 96, height: 72, "
                "seed: 4}\n", f"  format: generic\n  root: {data}\n"))
        out = os.path.join(self.dir, "colour_out")
        shutil.rmtree(out, ignore_errors=True)
        common.occgt("covis", recipe, "--out", out)
        common.occgt("tuples", recipe, "--out", out, "--shards")
        checked = 0
        for s in common.read_shard_samples(os.path.join(out, "views")):
            meta = s["json"]
            want = [colour_K[meta["scene"] + "/" + f["id"]] for f in meta["frames"]]
            # The colour images are 96 x 72 = W x H: the colour K is taken as it is.
            np.testing.assert_allclose(np.array(meta["image"]["K"]), np.array(want), rtol=1e-12)
            np.testing.assert_allclose(np.array(meta["K"]), s["intrinsics"], rtol=1e-12)
            self.assertFalse(np.allclose(s["intrinsics"], np.array(want)))
            checked += 1
        self.assertGreater(checked, 0)


class ShippedRecipe(unittest.TestCase):
    def test_tartanair_tuples_shards(self) -> None:
        """docs/RECIPES.md's example `occgt tuples recipes/tartanair-tuples.yaml --out
        out/ta-tuples --shards` on the real TartanAir sample: a few samples' bits equal
        views_ground_truth of the frames occgt's reader loads, with the recipe's options."""
        common.shared("tartanair/hospital_sample")
        recipe = os.path.join(common.SOURCE, "recipes", "tartanair-tuples.yaml")
        out = common.scratch("views_shards_tartanair")
        env = dict(os.environ, OCCGT_SHARED_DATA=common.SHARED)
        for cmd in (["covis", recipe, "--out", out],
                    ["tuples", recipe, "--out", out, "--shards"]):
            r = subprocess.run([common.BINARY, *cmd], capture_output=True, text=True, env=env)
            self.assertEqual(r.returncode, 0, r.stderr)
        ds = occgt.open_dataset(os.path.join(common.SHARED, "tartanair", "hospital_sample"),
                                "tartanair")
        samples = common.read_shard_samples(os.path.join(out, "views"))
        with open(os.path.join(out, "tuples.jsonl")) as f:
            self.assertEqual(len(samples), sum(1 for _ in f))
        with open(os.path.join(common.SOURCE, "schemas", "views_sample.schema.json")) as f:
            schema = json.load(f)
        for s in samples[::5]:
            meta = s["json"]
            jsonschema.validate(meta, schema)
            scene = ds.scene(meta["scene"])
            frames = [scene.load(f["id"], 640, 480) for f in meta["frames"]]
            for i, f in enumerate(frames):
                np.testing.assert_array_equal(s[f"depth{i}"], f[0])
            t = meta["tracks"]
            truth = occgt.views_ground_truth(
                [f[0] for f in frames], [f[1] for f in frames], [f[2] for f in frames],
                max_depth_m=None, dataset_depth_range=(scene.min_depth_m, scene.max_depth_m),
                dataset_max_depth_m=100.0, num_tracks=t["num_tracks"], seed=t["seed"])
            self.assertEqual(truth["label_options"], meta["label_options"])
            for name in ["visible_in", "occluded_in", "valid", "queries", "track_state",
                         "track_xy", "track_depth"]:
                np.testing.assert_array_equal(s[name], truth[name], err_msg=name)  # type: ignore
            self.assertGreater(meta["metrics"]["counts"]["OCCLUDED"], 0)
        # occgt.torch.TupleShardDataset reads these shards as TupleIndexDataset computes the
        # same tuples from the real frames (tests/python/tuple_shards_test.py: every key).
        from occgt.torch import TupleIndexDataset, TupleShardDataset
        stored = TupleShardDataset(os.path.join(out, "views"))
        computed = TupleIndexDataset(
            os.path.join(out, "tuples.jsonl"),
            os.path.join(common.SHARED, "tartanair", "hospital_sample"), "tartanair",
            width=640, height=480, preset="default", seed=0, dataset_max_depth_m=100.0)
        self.assertEqual(len(stored), len(samples))
        for k in range(0, len(stored), 5):
            a, b = stored[k], computed[k]
            self.assertEqual(list(a), list(b))
            for key in a:
                if hasattr(a[key], "dtype"):
                    self.assertEqual(a[key].dtype, b[key].dtype, key)
                    np.testing.assert_array_equal(a[key].numpy(), b[key].numpy(), err_msg=key)
                else:
                    self.assertEqual(a[key], b[key], key)


if __name__ == "__main__":
    unittest.main()
