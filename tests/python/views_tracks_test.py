"""The tracks and the shard sizes of the N-view shards of `occgt tuples --shards`
(libgt/pipeline/views_write.h, docs/RECIPES.md selection.tuples.num_tracks / query_view,
shards.target_mb):

- selection.tuples.num_tracks / query_view other than the defaults reach every sample: its
  JSON states them, and its queries, track_xy, track_depth and track_state equal
  occgt.views_ground_truth of the sample's frames with those arguments (and the stated seed);
  without the keys the samples carry the defaults of views_ground_truth's signature.
- shards.target_mb sizes the N-view shards as the pair shards: a tiny target gives one sample
  per shard, a large one a single shard, and a middle one the count of the documented estimate
  (EstimatedViewsSampleBytes, computed here), whatever samples_per_shard says.
- A query_view not below selection.views' smallest N, and a negative num_tracks, are refused
  with one line naming the key."""
from __future__ import annotations

import inspect
import json
import math
import os
import shutil
import subprocess
import unittest
from typing import Any, Dict, List

import numpy as np

import common
import occgt

RECIPE = """name: views-tracks-test
split: vt
seed: 11
resolution: [96, 72]
dataset:
  format: synthetic
  synthetic: {scenes: 2, frames: 10, width: 96, height: 72, seed: 4}
  frame_stride: 1
  min_valid_depth_fraction: 0.3
labels: {preset: default}
selection:
  pruning: {max_distance_m: 4.0, max_view_angle_deg: 120, frustum: true}
  score_stride: 4
  views: [3, 5]
  tuples: {edge_threshold: 0.2, pair_covisibility: [0.0, 0.97], restarts: 4, quota_per_scene: 4%TRACKS%}
occupancy: {enabled: false}
shards: {samples_per_shard: 100%TARGET%}
sample: {image: png, depth: true, labels: true, occupancy: false}
"""


def recipe_text(tracks: str = "", target: str = "") -> str:
    return RECIPE.replace("%TRACKS%", tracks).replace("%TARGET%", target)


def estimated_sample_bytes(width: int, height: int, views: int, tracks: int) -> int:
    """docs/MULTIVIEW.md "N-view shards": the estimate of one sample (PNG images, deflate;
    synthetic depth: 0.8 of its bytes left by deflate)."""
    px = width * height
    per_view = 0.8 * 4 * px + 0.06 * 9 * px + 0.9 * 13 * tracks + 2 * px
    return math.ceil(4096 + 8 * tracks + views * per_view)


def planned_sizes(views: List[int], target_bytes: int) -> List[int]:
    """Shards filled in order while the estimates of their tuples sum to at most the target."""
    sizes: List[int] = []
    total = 0
    for n in views:
        sample = estimated_sample_bytes(96, 72, n, 512)
        if not sizes or total + sample > target_bytes:
            sizes.append(0)
            total = 0
        sizes[-1] += 1
        total += sample
    return sizes


class ViewsTracks(unittest.TestCase):
    @classmethod
    def setUpClass(cls) -> None:
        cls.dir = common.scratch("views_tracks")
        cls.data = os.path.join(cls.dir, "data")
        cls.graphs = os.path.join(cls.dir, "graphs")
        cls.recipe_default = cls.write("default.yaml", recipe_text())
        common.occgt("covis", cls.recipe_default, "--out", cls.graphs, "--root", cls.data)

    @classmethod
    def write(cls, name: str, text: str) -> str:
        path = os.path.join(cls.dir, name)
        with open(path, "w") as f:
            f.write(text)
        return path

    def tuples(self, name: str, recipe: str) -> Dict[str, Any]:
        out = os.path.join(self.dir, name)
        shutil.rmtree(out, ignore_errors=True)
        shutil.copytree(os.path.join(self.graphs, "covisibility"), os.path.join(out, "covisibility"))
        summary = json.loads(common.occgt("tuples", recipe, "--out", out, "--shards", "--json",
                                          "--root", self.data).stdout)
        summary["out"] = out
        return summary

    def check_tracks(self, out: str, num_tracks: int, query_view: int) -> int:
        ds = occgt.open_dataset(self.data, "generic")
        samples = common.read_shard_samples(os.path.join(out, "views"), images=False)
        self.assertGreaterEqual(len(samples), 4)
        for s in samples:
            meta = s["json"]
            t = meta["tracks"]
            self.assertEqual((t["num_tracks"], t["query_view"]), (num_tracks, query_view))
            self.assertEqual(t["seed"], 11 + meta["tuple_index"])
            scene = ds.scene(meta["scene"])
            frames = [scene.load(f["id"], 96, 72) for f in meta["frames"]]
            truth = occgt.views_ground_truth(
                [f[0] for f in frames], [f[1] for f in frames], [f[2] for f in frames],
                num_tracks=num_tracks, query_view=query_view, seed=t["seed"],
                dataset_depth_range=(scene.min_depth_m, scene.max_depth_m))
            self.assertTrue(0 < len(truth["queries"]) <= num_tracks)
            self.assertEqual(s["queries"].shape, (len(truth["queries"]), 2))
            self.assertEqual(s["track_state"].shape, (meta["num_views"], len(truth["queries"])))
            for name in ["queries", "track_xy", "track_depth", "track_state", "visible_in"]:
                np.testing.assert_array_equal(s[name], truth[name], err_msg=name)  # type: ignore
            # The queries are pixels of the query view with depth.
            q = s["queries"]
            self.assertTrue((s["depth%d" % query_view][q[:, 1], q[:, 0]] > 0).all())
        return len(samples)

    def test_non_default_tracks(self) -> None:
        recipe = self.write("tracks.yaml", recipe_text(tracks=", num_tracks: 37, query_view: 2"))
        summary = self.tuples("tracks", recipe)
        self.check_tracks(summary["out"], 37, 2)

    def test_default_tracks_are_views_ground_truth_defaults(self) -> None:
        params = inspect.signature(occgt.views_ground_truth).parameters
        summary = self.tuples("defaults", self.recipe_default)
        self.check_tracks(summary["out"], params["num_tracks"].default, params["query_view"].default)
        # The defaults written out give the same samples' options digest as no keys (recipes
        # without the keys keep their digest).
        explicit = self.tuples("explicit", self.write("explicit.yaml", recipe_text(
            tracks=", num_tracks: %d, query_view: %d" % (params["num_tracks"].default,
                                                        params["query_view"].default))))
        digests = [{s["json"]["options_digest"] for s in common.read_shard_samples(os.path.join(o, "views"), images=False)}
                   for o in (summary["out"], explicit["out"])]
        self.assertEqual(len(digests[0]), 1)
        self.assertEqual(digests[0], digests[1])

    def test_target_mb_sizes_shards(self) -> None:
        tiny = self.tuples("tiny", self.write("tiny.yaml", recipe_text(target=", target_mb: 0.000001")))
        n = tiny["shards"]["samples"]
        self.assertGreaterEqual(n, 5)
        self.assertEqual(tiny["shards"]["shards"], n)  # one sample per shard, not 100
        large = self.tuples("large", self.write("large.yaml", recipe_text(target=", target_mb: 1000")))
        self.assertEqual(large["shards"]["shards"], 1)
        # A target beyond int64 bytes (legal: finite) is one shard too, not one per sample.
        huge = self.tuples("huge", self.write("huge.yaml", recipe_text(target=", target_mb: 1e300")))
        self.assertEqual(huge["shards"]["shards"], 1)
        # Tuples of 3 to 5 views: each counts at its own N, so that a shard of small tuples
        # holds more of them than one of large tuples (a uniform count at the largest N left
        # shards of small tuples far below the target).
        with open(os.path.join(tiny["out"], "tuples.jsonl")) as f:
            views = [len(json.loads(line)["frame_ids"]) for line in f]
        self.assertEqual(len(views), n)
        self.assertGreater(len(set(views)), 1, views)
        target_bytes = 2 * estimated_sample_bytes(96, 72, 4, 512)
        mid = self.tuples("mid", self.write(
            "mid.yaml", recipe_text(target=f", target_mb: {target_bytes / 1e6 + 1e-7!r}")))
        expected = planned_sizes(views, target_bytes)
        self.assertEqual(mid["shards"]["shards"], len(expected))
        samples = common.read_shard_samples(os.path.join(mid["out"], "views"), images=False)
        self.assertEqual(len(samples), n)
        with open(os.path.join(mid["out"], "views", "index.json")) as f:
            sizes = [s["nsamples"] for s in json.load(f)["shardlist"]]
        self.assertEqual(sizes, expected)
        # Counted at the largest N (5), every shard would hold one tuple.
        self.assertLess(len(sizes), n, (sizes, views))

    def test_bad_track_keys(self) -> None:
        for extra, key in ((", query_view: 3", "selection.tuples.query_view"),
                           (", num_tracks: -1", "selection.tuples.num_tracks")):
            recipe = self.write("bad.yaml", recipe_text(tracks=extra))
            r = subprocess.run([common.BINARY, "tuples", recipe, "--out", os.path.join(self.dir, "bad"),
                                "--root", self.data], capture_output=True, text=True)
            self.assertEqual(r.returncode, 1, r.stderr)
            self.assertEqual(r.stderr.count("\n"), 1, r.stderr)
            self.assertIn(key, r.stderr)


if __name__ == "__main__":
    unittest.main()
