"""occgt.torch.TupleShardDataset over the N-view shards of `occgt tuples --shards`
(docs/MULTIVIEW.md "Training on tuples"): every item equals TupleIndexDataset's item of the
same tuple (computed on the fly from the dataset) key for key and bit for bit, in both
"vggt" and "dust3r" forms, for deflate and uncompressed splits; occgt.views_seen_by gives
views_ground_truth's seen_by and histogram; a DataLoader with workers and collate_tuples
batches the items; bad splits and damaged samples raise ValueError naming the file."""
from __future__ import annotations

import io
import json
import os
import shutil
import tarfile
import unittest
from typing import Any, Callable, Dict, Tuple

import numpy as np
import torch

import common
import occgt
from occgt.torch import TupleIndexDataset, TupleShardDataset, collate_tuples

RECIPE = """name: tuple-shards-test
split: views
seed: 11
resolution: [96, 72]
dataset:
  format: generic
  root: {root}
  frame_stride: 1
  min_valid_depth_fraction: 0.3
labels: {{preset: default}}
selection:
  max_frame_gap: 0
  pruning: {{max_distance_m: 4.0, max_view_angle_deg: 120, frustum: true}}
  score_stride: 4
  overlap: [0.0, 1.0]
  visible_overlap: [0.0, 1.0]
  occlusion: [0.0, 1.0]
  quota_per_scene: 0
  views: [2, 4]
  tuples: {{edge_threshold: 0.2, pair_covisibility: [0.0, 0.97], restarts: 4,
            quota_per_scene: 3, num_tracks: 60}}
occupancy: {{enabled: false}}
shards: {{samples_per_shard: 2}}
sample: {{image: png, depth: true, labels: true, occupancy: false, compression: {compression}}}
"""


def assert_same_item(test: unittest.TestCase, a: Any, b: Any, where: str) -> None:
    """Equal keys, tensors equal in dtype, shape and bits, other values equal."""
    if isinstance(a, list):
        test.assertIsInstance(b, list, where)
        test.assertEqual(len(a), len(b), where)
        for k, (x, y) in enumerate(zip(a, b)):
            assert_same_item(test, x, y, f"{where}[{k}]")
        return
    test.assertEqual(list(a), list(b), where)
    for key in a:
        x, y = a[key], b[key]
        if isinstance(x, torch.Tensor):
            test.assertIsInstance(y, torch.Tensor, f"{where}.{key}")
            test.assertEqual((x.dtype, tuple(x.shape)), (y.dtype, tuple(y.shape)),
                             f"{where}.{key}")
            test.assertTrue(torch.equal(x, y), f"{where}.{key}")
        elif isinstance(x, np.ndarray):
            np.testing.assert_array_equal(x, y, f"{where}.{key}")
        else:
            test.assertEqual(x, y, f"{where}.{key}")


class TupleShards(unittest.TestCase):
    @classmethod
    def setUpClass(cls) -> None:
        cls.root = common.synth_dataset("tuple_shards_data", frames=9, resolution="96x72")
        cls.dir = common.scratch("tuple_shards")
        cls.out = {}
        for compression in ("deflate", "none"):
            recipe = os.path.join(cls.dir, f"{compression}.yaml")
            with open(recipe, "w") as f:
                f.write(RECIPE.format(root=cls.root, compression=compression))
            out = os.path.join(cls.dir, compression)
            common.occgt("covis", recipe, "--out", out)
            common.occgt("tuples", recipe, "--out", out, "--shards")
            cls.out[compression] = out
        cls.tuples = os.path.join(cls.out["deflate"], "tuples.jsonl")
        with open(cls.tuples) as f:
            cls.count = sum(1 for line in f if line.strip())

    def computed(self, **kw: Any) -> TupleIndexDataset:
        return TupleIndexDataset(self.tuples, self.root, "generic", width=96, height=72,
                                 preset="default", num_tracks=60, seed=11, **kw)

    def test_items_equal_the_computed_ones(self) -> None:
        self.assertGreaterEqual(self.count, 3)
        computed = self.computed()
        for compression, out in self.out.items():
            stored = TupleShardDataset(os.path.join(out, "views"))
            self.assertEqual(len(stored), self.count)
            sizes = set()
            for k in range(len(stored)):
                item = stored[k]
                assert_same_item(self, item, computed[k], f"{compression} item {k}")
                self.assertEqual(item["tuple_id"], k)
                self.assertEqual(stored.pair(k)["frame_ids"], list(item["frame_ids"]))
                sizes.add(int(item["depths"].shape[0]))
                # The stored bitmasks are the computed ones: not all empty.
                self.assertGreater(int((item["visible_in"] != 0).sum()), 0)
            self.assertGreaterEqual(len(sizes), 1)

    def test_recipe_query_view_and_max_depth(self) -> None:
        """A recipe with selection.tuples.query_view 1 and dataset.max_depth_m: its shards
        are TupleIndexDataset's items with query_view=1, dataset_max_depth_m= (the arguments
        docs/MULTIVIEW.md lists)."""
        text = RECIPE.format(root=self.root, compression="deflate")
        text = text.replace("num_tracks: 60}", "num_tracks: 60, query_view: 1}")
        text = text.replace("  frame_stride: 1\n", "  frame_stride: 1\n  max_depth_m: 3.5\n")
        self.assertEqual(text.count("query_view: 1"), 1)
        self.assertEqual(text.count("max_depth_m: 3.5"), 1)
        recipe = os.path.join(self.dir, "query_view.yaml")
        with open(recipe, "w") as f:
            f.write(text)
        out = os.path.join(self.dir, "query_view")
        common.occgt("covis", recipe, "--out", out)
        common.occgt("tuples", recipe, "--out", out, "--shards")
        stored = TupleShardDataset(os.path.join(out, "views"))
        computed = TupleIndexDataset(os.path.join(out, "tuples.jsonl"), self.root, "generic",
                                     width=96, height=72, preset="default", num_tracks=60,
                                     seed=11, query_view=1, dataset_max_depth_m=3.5)
        self.assertGreaterEqual(len(stored), 2)
        self.assertEqual(len(stored), len(computed))
        for k in range(len(stored)):
            assert_same_item(self, stored[k], computed[k], f"query_view item {k}")
        # Not the default's items: the query view and the depth range both matter.
        for kw, key in (({"dataset_max_depth_m": 3.5}, "tracks"),  # of view 0
                        ({"query_view": 1}, "point_masks")):  # depth up to the scene's range
            other = TupleIndexDataset(os.path.join(out, "tuples.jsonl"), self.root, "generic",
                                      width=96, height=72, preset="default", num_tracks=60,
                                      seed=11, **kw)  # type: ignore[arg-type]
            self.assertFalse(all(torch.equal(other[k][key], stored[k][key])
                                 for k in range(len(stored))), kw)

    def test_dust3r_views_equal_the_computed_ones(self) -> None:
        computed = self.computed(views="dust3r")
        stored = TupleShardDataset(os.path.join(self.out["deflate"], "views"), views="dust3r",
                                   dataset_name="generic")
        for k in range(len(stored)):
            assert_same_item(self, stored[k], computed[k], f"dust3r item {k}")

    def test_without_images(self) -> None:
        stored = TupleShardDataset(os.path.join(self.out["none"], "views"), images=False)
        computed = self.computed(images=False)
        assert_same_item(self, stored[0], computed[0], "images=False item 0")
        self.assertNotIn("images", stored[0])

    def test_seen_by_of_stored_bitmasks(self) -> None:
        stored = TupleShardDataset(os.path.join(self.out["none"], "views"))
        scene = occgt.open_dataset(self.root, "generic").scene(stored[0]["scene_id"])
        frames = [scene.load(i, 96, 72) for i in stored[0]["frame_ids"]]
        truth = occgt.views_ground_truth(
            [f[0] for f in frames], [f[1] for f in frames], [f[2] for f in frames],
            num_tracks=0, dataset_depth_range=(scene.min_depth_m, scene.max_depth_m))
        got = occgt.views_seen_by(truth["visible_in"], truth["valid"])
        np.testing.assert_array_equal(got["seen_by"], truth["seen_by"])
        np.testing.assert_array_equal(got["seen_by_histogram"], truth["seen_by_histogram"])
        # Against a direct count: popcount of the other views' bits.
        n = truth["visible_in"].shape[0]
        for i in range(n):
            others = truth["visible_in"][i] & np.uint32(~(1 << i) & 0xFFFFFFFF)
            count = np.zeros(others.shape, np.uint8)
            for j in range(n):
                count += ((others >> np.uint32(j)) & np.uint32(1)).astype(np.uint8)
            np.testing.assert_array_equal(got["seen_by"][i], count)
            hist = np.bincount(count[truth["valid"][i] == 1], minlength=n)
            np.testing.assert_array_equal(got["seen_by_histogram"][i], hist)
        # Bad bitmasks: a bit for a view the tuple does not have, valid not 0/1, dtypes.
        vis = truth["visible_in"].copy()
        vis[0, 0, 0] |= np.uint32(1 << n)
        with self.assertRaisesRegex(ValueError, "visible_in: bit for a view >= "):
            occgt.views_seen_by(vis, truth["valid"])
        valid = truth["valid"].copy()
        valid[0, 0, 0] = 2
        with self.assertRaisesRegex(ValueError, "valid: expected 0 or 1, got 2"):
            occgt.views_seen_by(truth["visible_in"], valid)
        with self.assertRaisesRegex(ValueError, "visible_in: expected uint32"):
            occgt.views_seen_by(truth["visible_in"].astype(np.int64), truth["valid"])
        with self.assertRaisesRegex(ValueError, "valid: expected uint8 of visible_in's shape"):
            occgt.views_seen_by(truth["visible_in"], truth["valid"][:1])

    def test_dataloader_with_workers(self) -> None:
        stored = TupleShardDataset(os.path.join(self.out["deflate"], "views"))
        stored[0]  # files opened in this process before the workers fork
        loader = torch.utils.data.DataLoader(stored, batch_size=2, num_workers=2,
                                             collate_fn=collate_tuples)
        batches = list(loader)
        self.assertEqual(sum(len(b["tuple_id"]) for b in batches), len(stored))
        first = collate_tuples([stored[0], stored[1]])
        for key, value in first.items():
            if isinstance(value, torch.Tensor):
                self.assertTrue(torch.equal(value, batches[0][key]), key)

    def test_bad_splits(self) -> None:
        out = self.out["none"]
        with self.assertRaisesRegex(ValueError, "index.json: missing; the N-view shards of "
                                                "occgt tuples --shards are in .*views"):
            TupleShardDataset(out)
        with self.assertRaisesRegex(ValueError, "views: expected 'vggt' or 'dust3r'"):
            TupleShardDataset(os.path.join(out, "views"), views="vgg")
        # A pair split (occgt build's samples) is named as such.
        pair_dir = common.scratch("tuple_shards_pairs")
        self.write_split(pair_dir, {"a/0_1.json": b"{}", "a/0_1.label01.npy":
                                    common.npy_bytes(np.zeros((2, 2), np.uint8))})
        with self.assertRaisesRegex(ValueError, "is a pair sample of occgt build"):
            TupleShardDataset(pair_dir)
        # A damaged sample: a bit set for a view the tuple does not have.
        bad = common.scratch("tuple_shards_bad")
        shutil.copytree(os.path.join(out, "views"), os.path.join(bad, "views"))
        views = os.path.join(bad, "views")
        shard = os.path.join(views, json.load(open(os.path.join(views, "index.json")))
                             ["shardlist"][0]["url"])
        with tarfile.open(shard) as t:
            m = next(x for x in t.getmembers() if x.name.endswith("visible_in.npy"))
            array = np.load(io.BytesIO(t.extractfile(m).read()))  # type: ignore[union-attr]
            data_offset = m.offset_data + len(common.npy_bytes(array)) - array.nbytes
        with open(shard, "r+b") as f:
            f.seek(data_offset + 3)  # the high byte of the first word (little-endian)
            f.write(bytes([0x80]))
        ds = TupleShardDataset(views)
        with self.assertRaisesRegex(ValueError, r"views-000000\.tar: .*visible_in\.npy: bit for "
                                                r"a view >= \d"):
            ds[0]
        # A sample without a member every N-view sample has.
        missing = common.scratch("tuple_shards_missing")
        self.write_split(missing, {"a/tuple_000000.json": b"{}",
                                   "a/tuple_000000.visible_in.npy":
                                   common.npy_bytes(np.zeros((1, 2, 2), np.uint32))})
        with self.assertRaisesRegex(ValueError, "has no intrinsics.npy member"):
            TupleShardDataset(missing)

    def damaged(self, name: str, change: Callable[[Dict[str, Any]], None]) -> str:
        """A copy of the uncompressed split whose first sample's members (field -> bytes, the
        json and .npy members as a dict and arrays) are rewritten by change."""
        views = os.path.join(common.scratch(name), "views")
        shutil.copytree(os.path.join(self.out["none"], "views"), views)
        index_path = os.path.join(views, "index.json")
        index = json.load(open(index_path))
        shard = os.path.join(views, index["shardlist"][0]["url"])
        with tarfile.open(shard) as t:
            members = [(m.name, t.extractfile(m).read())  # type: ignore[union-attr]
                       for m in t.getmembers()]
        key = members[0][0].split(".")[0]
        fields: Dict[str, Any] = {}
        for member, data in members:
            if member.split(".")[0] == key:
                field = member[len(key) + 1:]
                fields[field] = (json.loads(data) if field == "json" else
                                 np.load(io.BytesIO(data)) if field.endswith(".npy") else data)
        change(fields)
        with tarfile.open(shard, "w", format=tarfile.USTAR_FORMAT) as t:
            rewritten = [(f"{key}.{field}", json.dumps(v).encode() if field == "json" else
                          common.npy_bytes(v) if field.endswith(".npy") else v)
                         for field, v in fields.items()]
            for member, data in rewritten + [m for m in members
                                             if m[0].split(".")[0] != key]:
                info = tarfile.TarInfo(member)
                info.size = len(data)
                t.addfile(info, io.BytesIO(data))
        index["shardlist"][0]["filesize"] = os.path.getsize(shard)
        with open(index_path, "w") as f:
            json.dump(index, f)
        return views

    def test_damaged_samples(self) -> None:
        def set_json(field: str, value: Any) -> Callable[[Dict[str, Any]], None]:
            return lambda m: m["json"].__setitem__(field, value)

        def set_array(field: str, at: Any, value: Any) -> Callable[[Dict[str, Any]], None]:
            return lambda m: m[field].__setitem__(at, value)

        def scale_pose(m: Dict[str, Any]) -> None:  # in the json and the array alike
            m["world_from_cam.npy"][1, :3, :3] *= 1.03  # det 1.09: within the old 0.1
            m["json"]["world_from_cam"] = m["world_from_cam.npy"].tolist()

        def zero_focal(m: Dict[str, Any]) -> None:  # in the json and the array alike
            m["intrinsics.npy"][0, 0, 0] = 0.0
            m["json"]["K"] = m["intrinsics.npy"].tolist()

        def add_json(field: str, value: int) -> Callable[[Dict[str, Any]], None]:
            def change(m: Dict[str, Any]) -> None:
                node = m["json"]
                *path, last = field.split(".")
                for k in path:
                    node = node[k]
                node[last] += value
            return change

        def swap_queries(m: Dict[str, Any]) -> None:
            m["queries.npy"][[0, 1]] = m["queries.npy"][[1, 0]]

        def frame_number_text(m: Dict[str, Any]) -> None:
            m["json"]["frames"][0]["number"] = str(m["json"]["frames"][0]["number"])

        def at_valid_pixel(edit: Callable[[Dict[str, Any], Tuple[int, int, int]], None]
                           ) -> Callable[[Dict[str, Any]], None]:
            """edit(members, (0, v, u)) at the first valid pixel of view 0."""
            def change(m: Dict[str, Any]) -> None:
                v, u = np.argwhere(m["valid.npy"][0] == 1)[0]
                edit(m, (0, int(v), int(u)))
            return change

        def occlude_own_pixel(m: Dict[str, Any], at: Tuple[int, int, int]) -> None:
            m["occluded_in.npy"][at] |= np.uint32(1)  # view 0 occluded in itself

        def clear_diagonal(m: Dict[str, Any], at: Tuple[int, int, int]) -> None:
            m["visible_in.npy"][at] &= np.uint32(0xFFFFFFFE)

        def invalidate(m: Dict[str, Any], at: Tuple[int, int, int]) -> None:
            m["valid.npy"][at] = 0  # its bits stay

        def lose_visible_track(m: Dict[str, Any]) -> None:
            k = int(np.argwhere(m["track_state.npy"][0] == occgt.TRACK_VISIBLE)[0][0])
            m["track_xy.npy"][0, k] = np.nan

        cases = [  # (change, the message after the sample's name); each was read before
            (set_json("tuple_index", "0"), r"\.json: .*tuple_index: expected an integer"),
            (set_json("num_views", 3.0), r"\.json: .*num_views: expected an integer 1\.\.32"),
            (set_json("resolution", [96.0, 72]), r"\.json: .*resolution: expected an integer"),
            (set_json("scene", None), r"\.json: .*scene: expected a non-empty string"),
            (frame_number_text, r"\.json: .*frames: expected num_views \(\d+\) objects"),
            (set_json("key", "a/tuple_000009"), r"\.json: .*key 'a/tuple_000009', expected "
                                                r"the sample's"),
            (scale_pose, r"\.json: world_from_cam\[1\]: rotation is not orthonormal "
                         r"\(\|R\^T R - I\| = 0\.0609 > 0\.001\)"),
            (zero_focal, r"\.json: K\[0\]: .*focal"),
            (set_array("intrinsics.npy", (0, 0, 0), 0.0), r"\.intrinsics\.npy: view 0 \(0, 0\) "
                                                          r"holds 0, the json's K\[0\] says"),
            (set_array("world_from_cam.npy", (2, 0, 3), 7.0),
             r"\.world_from_cam\.npy: view 2 \(0, 3\) holds 7, the json's world_from_cam\[2\]"),
            (set_array("occluded_in.npy", (0, 0, 0), np.uint32(1 << 31)),
             r"\.occluded_in\.npy: bit for a view >= \d"),
            (set_array("track_state.npy", (0, 0), 9), r"\.track_state\.npy: expected 0\.\.4, "
                                                      r"got 9 at element 0"),
            (set_array("track_xy.npy", (0, 0, 0), np.inf), r"\.track_xy\.npy: expected \(x, y\) "
                                                           r"both finite or both NaN"),
            (at_valid_pixel(occlude_own_pixel), r"\.occluded_in\.npy: a pixel both VISIBLE "
                                                r"\(visible_in\) and OCCLUDED in one view"),
            (at_valid_pixel(clear_diagonal), r"\.visible_in\.npy: view 0's own bit \(the "
                                             r"diagonal\) not set for a valid pixel"),
            (at_valid_pixel(invalidate), r"\.valid\.npy: view 0 pixel \(\d+, \d+\) holds 0; "
                                         r"its depth [0-9.]+ m is valid"),
            (lose_visible_track, r"\.track_xy\.npy: NaN for a track whose state is VISIBLE"),
            (set_array("depth1.npy", (0, 0), np.nan), r"\.depth1\.npy: pixel \(0, 0\) holds "
                                                      r"nan; expected metres >= 0"),
            (set_array("depth1.npy", (0, 0), -1.0), r"\.depth1\.npy: pixel \(0, 0\) holds -1; "
                                                    r"expected metres >= 0"),
            (add_json("metrics.counts.VISIBLE", 1), r"\.visible_in\.npy: its counts\.VISIBLE is "
                                                    r"\d+, the json's metrics\.counts\.VISIBLE"),
            (swap_queries, r"\.queries\.npy: query 0 is \(\d+, \d+\); the sampling of view 0"),
            (add_json("tracks.seed", 1), r"\.queries\.npy: query \d+ is .* with tracks\.seed"),
        ]
        for n, (change, message) in enumerate(cases):
            ds = TupleShardDataset(self.damaged("tuple_shards_damaged", change))
            with self.assertRaisesRegex(ValueError, r"views-000000\.tar: \w+/tuple_000000" +
                                        message, msg=f"case {n}"):
                ds[0]
            ds[1]  # the other samples are read as before

    def test_bad_arguments_and_indexes(self) -> None:
        views = os.path.join(self.out["none"], "views")
        with self.assertRaisesRegex(TypeError, "images: expected a bool, got str"):
            TupleShardDataset(views, images="no")  # type: ignore[arg-type]
        with self.assertRaisesRegex(TypeError, "dataset_name: expected a str, got int"):
            TupleShardDataset(views, views="dust3r", dataset_name=5)  # type: ignore[arg-type]
        # index.json with a count of another type: named, not "2 samples, ... says 2".
        copy = os.path.join(common.scratch("tuple_shards_index"), "views")
        shutil.copytree(views, copy)
        index = json.load(open(os.path.join(copy, "index.json")))
        index["shardlist"][0]["nsamples"] = str(index["shardlist"][0]["nsamples"])
        with open(os.path.join(copy, "index.json"), "w") as f:
            json.dump(index, f)
        with self.assertRaisesRegex(ValueError, r"index\.json: shardlist\[0\]\.nsamples: "
                                                r"expected an integer >= 0"):
            TupleShardDataset(copy)
        # A shard removed after the split was indexed (e.g. before a DataLoader worker opens
        # it): a ValueError naming it, not FileNotFoundError.
        shutil.rmtree(copy)
        shutil.copytree(views, copy)
        ds = TupleShardDataset(copy)
        os.remove(os.path.join(copy, "views-000000.tar"))
        with self.assertRaisesRegex(ValueError, r"views-000000\.tar: shard missing \(removed "
                                                r"since it was indexed\)"):
            ds[0]

    @staticmethod
    def write_split(folder: str, members: dict) -> None:
        shard = os.path.join(folder, "x-000000.tar")
        with tarfile.open(shard, "w", format=tarfile.USTAR_FORMAT) as t:
            for name, data in members.items():
                info = tarfile.TarInfo(name)
                info.size = len(data)
                t.addfile(info, io.BytesIO(data))
        with open(os.path.join(folder, "index.json"), "w") as f:
            json.dump({"__kind__": "wids-shard-index-v1", "wids_version": 1, "shardlist": [
                {"url": "x-000000.tar", "nsamples": 1,
                 "filesize": os.path.getsize(shard)}]}, f)


if __name__ == "__main__":
    unittest.main()
