"""occgt covis and occgt tuples (libgt/pipeline/covisibility.h, tuple_stage.h,
docs/MULTIVIEW.md): the covisibility graph of
each scene equals the pair scorer's values (the select stage of `occgt build` with every
candidate kept: no frame gap, no filters, no quota), the same bytes with 1 and 2 threads and
with the scenes split over 2 tasks (and with --dense run on a folder written without it), the
dense matrix is the sparse graph laid out (MapAnything's orientation), a re-run skips finished scenes, and a graph of other options is refused; the
tuples satisfy every constraint, carry the graph's values, are seeded and identical over
graphs of any thread count or task split."""
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

RECIPE = """name: covis-test
split: covis
seed: 0
resolution: [160, 120]
dataset:
  format: synthetic
  synthetic: {scenes: 3, frames: 14, width: 160, height: 120, seed: 3}
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
  tuples: {edge_threshold: 0.2, pair_covisibility: [0.0, 0.97], restarts: 4, quota_per_scene: 6}
occupancy: {enabled: false}
sample: {image: none, depth: true, labels: true, occupancy: false}
"""


def read_dir(out: str) -> Dict[str, bytes]:
    files = {}
    for p in sorted(glob.glob(os.path.join(out, "covisibility", "**", "*"), recursive=True)):
        if os.path.isfile(p):
            files[os.path.relpath(p, out)] = common.read_bytes(p)
    return files


class Covis(unittest.TestCase):
    @classmethod
    def setUpClass(cls) -> None:
        cls.dir = common.scratch("covis")
        cls.recipe = os.path.join(cls.dir, "recipe.yaml")
        with open(cls.recipe, "w") as f:
            f.write(RECIPE)
        cls.data = os.path.join(cls.dir, "data")
        cls.out1 = os.path.join(cls.dir, "t1")
        common.occgt("covis", cls.recipe, "--out", cls.out1, "--threads", 1, "--dense",
                     "--root", cls.data)

    def test_equals_the_pair_scorer(self) -> None:
        sel = os.path.join(self.dir, "select")
        common.occgt("build", self.recipe, "--out", sel, "--stage", "select", "--root", self.data)
        scored: Dict[Tuple[str, str, str], Tuple[float, float, float, float]] = {}
        for path in glob.glob(os.path.join(sel, "selection", "*.jsonl")):
            with open(path) as f:
                rows = [json.loads(line) for line in f]
            for p in rows:
                m01, m10 = p["score_metrics"]["01"], p["score_metrics"]["10"]
                self.assertEqual(p["score_stride"], 4)
                scored[(p["scene"], p["frame0"]["id"], p["frame1"]["id"])] = (
                    m01["consistent_overlap"], m10["consistent_overlap"], m01["overlap"],
                    m10["overlap"])
        graphs = sorted(glob.glob(os.path.join(self.out1, "covisibility", "*.npz")))
        self.assertEqual(len(graphs), 3)
        seen = 0
        for path in graphs:
            g = np.load(path)
            scene = os.path.basename(path)[:-4]
            ids = list(g["frame_ids"])
            self.assertEqual(g["i"].dtype, np.int32)
            self.assertEqual(g["c_ij"].dtype, np.float32)
            self.assertTrue(np.all(g["i"] < g["j"]))
            self.assertEqual(int(g["score_stride"]), 4)
            for k in range(len(g["i"])):
                key = (scene, ids[g["i"][k]], ids[g["j"][k]])
                self.assertIn(key, scored)
                want = np.array(scored.pop(key), dtype=np.float32)
                got = np.array([g["c_ij"][k], g["c_ji"][k], g["o_ij"][k], g["o_ji"][k]])
                np.testing.assert_array_equal(got, want, err_msg=str(key))
                seen += 1
            # Dense: C[i, j] = c_ij, C[j, i] = c_ji, diagonal self, 0 elsewhere.
            n = len(ids)
            dense = np.load(os.path.join(self.out1, "covisibility", scene,
                                         f"pairwise_covisibility--{n}x{n}.npy"))
            self.assertEqual(dense.dtype, np.float32)
            expect = np.zeros((n, n), np.float32)
            expect[g["i"], g["j"]] = g["c_ij"]
            expect[g["j"], g["i"]] = g["c_ji"]
            expect[np.arange(n), np.arange(n)] = g["self"]
            np.testing.assert_array_equal(dense, expect)
            self.assertTrue(np.all(g["self"] > 0.3))  # a frame sees its valid pixels
        self.assertEqual(scored, {})  # every scored pair is in a graph
        self.assertGreater(seen, 50)
        # Pruning dropped some pairs (the graph is sparse) and kept some.
        counts = json.loads(common.occgt("covis", self.recipe, "--out", self.out1, "--json",
                                         "--root", self.data).stdout)
        with open(os.path.join(common.SOURCE, "schemas", "covis_summary.schema.json")) as f:
            jsonschema.validate(counts, json.load(f))
        self.assertEqual(counts["skipped_complete"], 3)
        self.assertEqual(counts["written"], 0)

    def test_same_bytes_for_threads_and_tasks(self) -> None:
        out2 = os.path.join(self.dir, "t2")
        common.occgt("covis", self.recipe, "--out", out2, "--threads", 2, "--dense",
                     "--root", self.data)
        split = os.path.join(self.dir, "split")
        for k in range(2):
            r = common.occgt("covis", self.recipe, "--out", split, "--threads", 2, "--dense",
                             "--task", k, "--tasks", 2, "--root", self.data)
            # The text says that a task wrote its share only (exit 0 for half the scenes).
            self.assertTrue(r.stdout.startswith(f"task {k} of 2 (--task/--tasks): its share of "
                                                "the scenes only; "), r.stdout)
        # A first run without --dense, then --dense on the complete folder: the matrices are
        # written from the stored graphs, the same bytes.
        later = os.path.join(self.dir, "later")
        common.occgt("covis", self.recipe, "--out", later, "--root", self.data)
        self.assertFalse(any(k.endswith(".npy") for k in read_dir(later)))
        common.occgt("covis", self.recipe, "--out", later, "--dense", "--root", self.data)
        one = read_dir(self.out1)
        self.assertGreater(len(one), 5)
        self.assertEqual(one, read_dir(out2))
        self.assertEqual(one, read_dir(split))
        self.assertEqual(one, read_dir(later))
        # A dense matrix cut short is written again from the graph (it used to be kept).
        cut = next(os.path.join(later, k) for k in sorted(read_dir(later)) if k.endswith(".npy"))
        with open(cut, "r+b") as f:
            f.truncate(os.path.getsize(cut) // 2)
        common.occgt("covis", self.recipe, "--out", later, "--dense", "--root", self.data)
        self.assertEqual(one, read_dir(later))

    def test_another_recipe_is_refused_and_bad_flags_exit_2(self) -> None:
        other = os.path.join(self.dir, "other.yaml")
        with open(other, "w") as f:
            f.write(RECIPE.replace("score_stride: 4", "score_stride: 8"))
        r = subprocess.run([common.BINARY, "covis", other, "--out", self.out1, "--root",
                            self.data], capture_output=True, text=True)
        self.assertEqual(r.returncode, 1)
        self.assertIn("written under another recipe", r.stderr)
        r = subprocess.run([common.BINARY, "covis", self.recipe, "--out", self.out1, "--task",
                            "2", "--tasks", "2"], capture_output=True, text=True)
        self.assertEqual(r.returncode, 2)
        self.assertIn("--task: expected 0 <= task < tasks, got task 2 of 2", r.stderr)
        r = subprocess.run([common.BINARY, "covis", self.recipe, "--out", self.out1, "--task",
                            "1"], capture_output=True, text=True)
        self.assertEqual(r.returncode, 2)
        self.assertIn("--task: expected 0 <= task < tasks, got task 1 of 1 (--tasks N gives the "
                      "number of tasks)", r.stderr)

    def test_tuples(self) -> None:
        r = json.loads(common.occgt("tuples", self.recipe, "--out", self.out1, "--json",
                                    "--root", self.data).stdout)
        with open(os.path.join(common.SOURCE, "schemas", "tuples_summary.schema.json")) as f:
            jsonschema.validate(r, json.load(f))
        self.assertEqual(r["scenes_without_tuples"], [])
        self.assertEqual(sum(r["sizes"].values()), r["tuples"])  # report.json's word
        with open(os.path.join(common.SOURCE, "schemas", "tuples_line.schema.json")) as f:
            schema = json.load(f)
        text = common.read_bytes(os.path.join(self.out1, "tuples.jsonl"))
        lines = [json.loads(x) for x in text.decode().splitlines()]
        self.assertEqual(len(lines), r["tuples"])
        self.assertGreater(len(lines), 6)
        graphs = {}
        for path in glob.glob(os.path.join(self.out1, "covisibility", "*.npz")):
            g = np.load(path)
            ids = list(g["frame_ids"])
            n = len(ids)
            dense = np.zeros((n, n), np.float32)
            dense[g["i"], g["j"]] = g["c_ij"]
            dense[g["j"], g["i"]] = g["c_ji"]
            dense[np.arange(n), np.arange(n)] = g["self"]
            graphs[os.path.basename(path)[:-4]] = (ids, dense)
        per_scene: Dict[str, int] = {}
        sizes = set()
        drawn = set()
        for t in lines:
            jsonschema.validate(t, schema)
            ids, dense = graphs[t["scene"]]
            idx = [ids.index(i) for i in t["frame_ids"]]
            n = len(idx)
            sizes.add(n)
            self.assertTrue(3 <= n <= 5, t)
            sub = dense[np.ix_(idx, idx)]
            np.testing.assert_array_equal(np.array(t["covisibility"], np.float32), sub)
            score = np.float32(0.5) * (sub + sub.T)
            for k in range(1, n):  # each new view is a neighbour of an earlier one
                self.assertTrue(any(float(score[a, k]) >= 0.2 for a in range(k)), t)
            for a in range(n):
                for b in range(a + 1, n):
                    self.assertTrue(0.0 <= float(score[a, b]) <= 0.97, t)
            per_scene[t["scene"]] = per_scene.get(t["scene"], 0) + 1
            key = (t["scene"], tuple(sorted(t["frame_ids"])))
            self.assertNotIn(key, drawn)  # no tuple twice
            drawn.add(key)
        self.assertTrue(all(c <= 6 for c in per_scene.values()), per_scene)
        self.assertGreaterEqual(len(sizes), 2)  # sizes drawn in [3, 5]
        # Seeded: the same bytes again, and from the graphs of 2 threads / 2 tasks.
        common.occgt("tuples", self.recipe, "--out", self.out1, "--root", self.data)
        self.assertEqual(common.read_bytes(os.path.join(self.out1, "tuples.jsonl")), text)
        split = os.path.join(self.dir, "split_tuples")
        for k in range(2):
            common.occgt("covis", self.recipe, "--out", split, "--threads", 2, "--task", k,
                         "--tasks", 2, "--root", self.data)
        common.occgt("tuples", self.recipe, "--out", split, "--root", self.data)
        self.assertEqual(common.read_bytes(os.path.join(split, "tuples.jsonl")), text)
        # Another seed, other tuples.
        seeded = os.path.join(self.dir, "seed1.yaml")
        with open(seeded, "w") as f:
            f.write(RECIPE.replace("seed: 0", "seed: 1"))
        common.occgt("tuples", seeded, "--out", split, "--root", self.data)
        self.assertNotEqual(common.read_bytes(os.path.join(split, "tuples.jsonl")), text)
        # Without graphs: one line naming the missing file.
        r2 = subprocess.run([common.BINARY, "tuples", self.recipe, "--out",
                             os.path.join(self.dir, "none"), "--root", self.data],
                            capture_output=True, text=True)
        self.assertEqual(r2.returncode, 1)
        self.assertIn("missing: run `occgt covis`", r2.stderr)
        self.assertFalse(os.path.exists(os.path.join(self.dir, "none")))  # nor a lock file


class StaleGraphs(unittest.TestCase):
    """Graphs that no longer match the data are refused by name, not turned into samples
    without images or ground truth; covis keeps the build's frames (scan.no_color when images
    are stored); tuples names the scenes that gave no tuple; the text summaries print the
    drops; covis in a Slurm array prints its task."""

    def test_stale_graphs_and_reports(self) -> None:
        base = common.scratch("covis_stale")
        data = os.path.join(base, "data")
        common.occgt("synth", "--out", data, "--scenes", 3, "--frames", 14, "--resolution",
                     "160x120", "--seed", 3)
        text = RECIPE.replace("format: synthetic\n  synthetic: {scenes: 3, frames: 14, width: "
                              "160, height: 120, seed: 3}", "format: generic")
        self.assertNotEqual(text, RECIPE)
        text = text.replace("sample: {image: none,", "sample: {image: png,")
        recipe = os.path.join(base, "r.yaml")
        with open(recipe, "w") as f:
            f.write(text)

        def run(*args: object, env: Dict[str, str] = None) -> subprocess.CompletedProcess:
            return subprocess.run([common.BINARY, *map(str, args), "--root", data],
                                  capture_output=True, text=True, env=env)

        # A frame without colour is not kept when images are stored, and counted.
        os.remove(os.path.join(data, "synth_001", "color", "000005.png"))
        out = os.path.join(base, "out")
        r = run("covis", recipe, "--out", out)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("dropped: ", r.stdout)
        self.assertIn("scan.no_color 1", r.stdout)
        g = np.load(os.path.join(out, "covisibility", "synth_001.npz"))
        self.assertNotIn("000005", list(g["frame_ids"]))
        self.assertEqual(len(g["frame_ids"]), 13)
        r = run("tuples", recipe, "--out", out, "--shards")
        self.assertEqual(r.returncode, 0, r.stderr)

        def refused(message: str) -> None:
            shutil.rmtree(os.path.join(out, "views"), ignore_errors=True)  # complete: kept
            before = common.read_bytes(os.path.join(out, "tuples.jsonl"))
            r = run("tuples", recipe, "--out", out, "--shards")
            self.assertEqual(r.returncode, 1, r.stdout)
            self.assertEqual(len(r.stderr.splitlines()), 1, r.stderr)
            self.assertRegex(r.stderr, message)
            # Refused before anything is written: tuples.jsonl as it was, no N-view shards.
            self.assertEqual(common.read_bytes(os.path.join(out, "tuples.jsonl")), before)
            self.assertFalse(os.path.exists(os.path.join(out, "views")))

        # Data changed since the graph: a view's colour, its depth, its pose.
        with open(os.path.join(out, "tuples.jsonl")) as f:
            first = json.loads(f.readline())
        scene, view = first["scene"], first["frame_ids"][1]
        color = os.path.join(data, scene, "color", view + ".png")
        kept = common.read_bytes(color)
        os.remove(color)
        # (a frame of the graph without colour: refused with the graph, before any view)
        refused(scene + r"\.npz: frame_ids\[\d+\] '" + view + r"' has no colour image, which "
                r"sample\.image \(png\) needs: the data changed since occgt covis; re-run occgt "
                r"covis for it \(delete .*" + scene + r"\.npz first\)$")
        with open(color, "wb") as f:
            f.write(kept)
        depth = os.path.join(data, scene, "depth", view + ".npy")
        kept = common.read_bytes(depth)
        np.save(depth, np.zeros((120, 160), np.float32))
        # (checked for every view before anything is written: it used to replace tuples.jsonl
        # and write shards first)
        refused(scene + r"\.npz: frame_ids\[\d+\] '" + view + r"' has 0 valid depth pixels of "
                r"19200, below dataset\.min_valid_depth_fraction 0\.3")
        with open(depth, "wb") as f:
            f.write(kept)
        # A failure while the shards are written (a colour file cut after its header, which
        # the reader reads) names the file and says to remove DIR/views too.
        kept = common.read_bytes(color)
        with open(color, "wb") as f:
            f.write(kept[:len(kept) // 3])
        shutil.rmtree(os.path.join(out, "views"), ignore_errors=True)
        r = run("tuples", recipe, "--out", out, "--shards")
        self.assertEqual(r.returncode, 1, r.stdout)
        self.assertEqual(len(r.stderr.splitlines()), 1, r.stderr)
        self.assertTrue(r.stderr.startswith("occgt: error: " + color + ": truncated PNG"),
                        r.stderr)
        self.assertTrue(r.stderr.rstrip().endswith(
            "remove " + os.path.join(out, "views") + " too before a run on other graphs (it "
            "holds shards of these tuples)"), r.stderr)
        with open(color, "wb") as f:
            f.write(kept)
        manifest = os.path.join(data, "synth_002", "scene.json")
        kept = common.read_bytes(manifest)
        doc = json.loads(kept)
        graph_ids = list(np.load(os.path.join(out, "covisibility", "synth_002.npz"))["frame_ids"])
        doc["frames"][int(graph_ids[2])]["world_from_cam"][0][0] = 2.0
        with open(manifest, "w") as f:
            json.dump(doc, f)
        refused(r"synth_002\.npz: frame_ids\[2\] '" + graph_ids[2] + r"' is a frame the dataset "
                r"now marks unusable \(pose: ")
        with open(manifest, "wb") as f:
            f.write(kept)
        kept_manifest = kept
        # frame_ids out of the scene's order (their scores would go to the wrong frames).
        path = os.path.join(out, "covisibility", "synth_002.npz")
        kept = common.read_bytes(path)
        members = dict(np.load(path))
        ids = members["frame_ids"].copy()
        ids[[3, 4]] = ids[[4, 3]]
        members["frame_ids"] = ids
        np.savez(path, **members)
        order = (r"synth_002\.npz: frame_ids\[4\] '" + ids[4] + r"' comes before frame_ids\[3\] "
                 r"in the scene: expected the scene's order")
        refused(order)

        def covis_refuses(message: str) -> None:  # as tuples: not counted complete
            r = run("covis", recipe, "--out", out, "--dense")
            self.assertEqual(r.returncode, 1, r.stdout)
            *progress, last = r.stderr.splitlines()
            self.assertTrue(all(x.startswith("[covis] ") for x in progress), r.stderr)
            self.assertRegex(last, message)

        covis_refuses(order)
        with open(path, "wb") as f:
            f.write(kept)
        # A frame id of other data, every member emptied: refused by both, naming the file.
        for edit, message in [
                (lambda m: m["frame_ids"].__setitem__(-1, "999999"),
                 r"synth_002\.npz: frame_ids\[\d+\] '999999' is not a frame of scene synth_002"),
                (lambda m: m.update({k: m[k][:0] for k in
                                     ["frame_ids", "i", "j", "c_ij", "c_ji", "o_ij", "o_ji",
                                      "self"]}),
                 r"synth_002\.npz: frame_ids lacks frame '000000' of scene synth_002 \(frame_ids "
                 r"is empty\), which the recipe's scan keeps now: the data changed since occgt "
                 r"covis; re-run occgt covis for it \(delete .*synth_002\.npz first\)$")]:
            damaged = dict(np.load(path))
            damaged["frame_ids"] = damaged["frame_ids"].copy()
            edit(damaged)
            np.savez(path, **damaged)
            refused(message)
            covis_refuses(message)
        with open(path, "wb") as f:
            f.write(kept)
        # A broken scene manifest is read by covis too, not passed over as complete.
        with open(manifest, "w") as f:
            f.write("{")
        covis_refuses(r"synth_002/scene\.json: ")
        with open(manifest, "wb") as f:
            f.write(kept_manifest)
        # A stale graph: the frame without colour at covis time has it now, so the scan keeps
        # it and the graph lacks it.
        no_color = os.path.join(data, "synth_001", "color", "000005.png")
        shutil.copy(os.path.join(data, "synth_001", "color", "000004.png"), no_color)
        stale = (r"synth_001\.npz: frame_ids lacks frame '000005' of scene synth_001 \(before "
                 r"frame_ids\[5\] '000006'\), which the recipe's scan keeps now")
        refused(stale)
        covis_refuses(stale)
        os.remove(no_color)
        # Members of another shape, or a score_stride the digest does not hold: refused by
        # tuples, and by covis, which no longer counts such a graph complete.
        for member, value, message in [
                ("c_ij", members["c_ij"].reshape(1, -1),
                 r"c_ij\.npy: expected shape \[n\], got 2 dimensions"),
                ("score_stride", np.array([4], np.int32),
                 r"score_stride\.npy: expected a scalar \(shape \[\]\), got 1 dimensions"),
                ("score_stride", np.array(8, np.int32),
                 r"score_stride\.npy: 8, expected the recipe's 4")]:
            damaged = dict(np.load(path))
            damaged[member] = value
            np.savez(path, **damaged)
            refused(message)
            r = run("covis", recipe, "--out", out)
            self.assertEqual(r.returncode, 1, r.stdout)
            self.assertRegex(r.stderr, message + r".*: remove the file to compute the scene again")
            with open(path, "wb") as f:
                f.write(kept)
        r = run("tuples", recipe, "--out", out, "--shards")
        self.assertEqual(r.returncode, 0, r.stderr)

        # No neighbours at all: every scene is named, in --json (schema'd) and in the text (the
        # N-view shards of the other tuples would no longer match: removed first).
        shutil.rmtree(os.path.join(out, "views"))
        lonely = os.path.join(base, "lonely.yaml")
        with open(lonely, "w") as f:
            f.write(text.replace("edge_threshold: 0.2", "edge_threshold: 1.0"))
        r = run("tuples", lonely, "--out", out, "--json")
        self.assertEqual(r.returncode, 0, r.stderr)
        summary = json.loads(r.stdout)
        with open(os.path.join(common.SOURCE, "schemas", "tuples_summary.schema.json")) as f:
            jsonschema.validate(summary, json.load(f))
        self.assertEqual(summary["tuples"], 0)
        self.assertEqual(summary["scenes_without_tuples"], ["synth_000", "synth_001", "synth_002"])
        r = run("tuples", lonely, "--out", out)
        self.assertIn("3 scene(s) gave no tuple: synth_000, synth_001, synth_002", r.stdout)

        # A Slurm array task says which task it is, as occgt build does.
        env = dict(os.environ, SLURM_ARRAY_TASK_ID="1", SLURM_ARRAY_TASK_MIN="0",
                   SLURM_ARRAY_TASK_MAX="1", SLURM_ARRAY_TASK_COUNT="2")
        r = run("covis", recipe, "--out", os.path.join(base, "slurm"), env=env)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("[covis] task 1 of 2 (from SLURM_ARRAY_TASK_ID 1)", r.stderr)


class ShippedRecipe(unittest.TestCase):
    def test_tartanair_tuples(self) -> None:
        """docs/RECIPES.md's example: recipes/tartanair-tuples.yaml on the real TartanAir
        sample; a few graph values recomputed from pair_ground_truth's label01 at the stride."""
        common.shared("tartanair/hospital_sample")
        recipe = os.path.join(common.SOURCE, "recipes", "tartanair-tuples.yaml")
        out = common.scratch("covis_tartanair")
        env = dict(os.environ, OCCGT_SHARED_DATA=common.SHARED)
        for cmd in (["covis", recipe, "--out", out, "--dense"], ["tuples", recipe, "--out", out]):
            r = subprocess.run([common.BINARY, *cmd], capture_output=True, text=True, env=env)
            self.assertEqual(r.returncode, 0, r.stderr)
        graphs = glob.glob(os.path.join(out, "covisibility", "*.npz"))
        self.assertEqual(len(graphs), 1)
        g = np.load(graphs[0])
        self.assertGreater(len(g["i"]), 20)
        ds = occgt.open_dataset(os.path.join(common.SHARED, "tartanair", "hospital_sample"),
                                "tartanair")
        scene = ds.scene(ds.scenes()[0])
        ids = list(g["frame_ids"])
        for k in range(0, len(g["i"]), max(1, len(g["i"]) // 4)):
            a, b = ids[g["i"][k]], ids[g["j"][k]]
            (d0, K0, T0), (d1, K1, T1) = scene.load(a), scene.load(b)
            p = occgt.pair_ground_truth(d0, d1, K0, K1, T0, T1, max_depth_m=None,
                                        dataset_depth_range=(scene.min_depth_m,
                                                             scene.max_depth_m),
                                        dataset_max_depth_m=100.0)
            for label, c in ((p["label01"], g["c_ij"][k]), (p["label10"], g["c_ji"][k])):
                grid = label[::8, ::8]
                self.assertEqual(np.float32((grid == occgt.VISIBLE).sum() / grid.size), c)
        with open(os.path.join(common.SOURCE, "schemas", "tuples_line.schema.json")) as f:
            schema = json.load(f)
        with open(os.path.join(out, "tuples.jsonl")) as f:
            lines = [json.loads(x) for x in f]
        self.assertGreater(len(lines), 0)
        n = len(ids)
        dense = np.zeros((n, n), np.float32)
        dense[g["i"], g["j"]] = g["c_ij"]
        dense[g["j"], g["i"]] = g["c_ji"]
        for t in lines:
            jsonschema.validate(t, schema)
            self.assertTrue(4 <= len(t["frame_ids"]) <= 8)
            idx = [ids.index(i) for i in t["frame_ids"]]
            sub = dense[np.ix_(idx, idx)]
            score = np.float32(0.5) * (sub + sub.T)
            for a in range(len(idx)):  # the recipe's pair_covisibility [0.05, 0.95]
                self.assertTrue(any(float(score[b, a]) >= 0.25 for b in range(a)) or a == 0)
                for b in range(a + 1, len(idx)):
                    self.assertTrue(0.05 <= float(score[a, b]) <= 0.95, t)


if __name__ == "__main__":
    unittest.main()
