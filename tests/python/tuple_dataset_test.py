"""occgt.torch.TupleIndexDataset and collate_tuples (docs/MULTIVIEW.md): an item's ground truth
is occgt.views_ground_truth of its frames (same seed rule), VGGT's keys have their layouts
(extrinsics = inverse poses, images in [0, 1], track_vis_mask = VISIBLE), the DUSt3R list of
views carries the same arrays, tuples.jsonl is read into a TupleIndex whose columns give the
lines' tuples (slices, errors naming file:line, a forked child's reads), and tuples of 3 and
5 views collate with padding and a view mask; bad arguments raise ValueError."""
from __future__ import annotations

import gc
import json
import os
import pickle
import unittest

import numpy as np
import torch

import common
import occgt
from occgt.torch import (TRACK_STATE_PADDED, TupleIndex, TupleIndexDataset, TupleRef,
                         collate_tuples, read_tuples)


class TupleDataset(unittest.TestCase):
    @classmethod
    def setUpClass(cls) -> None:
        cls.root = common.synth_dataset("tuple_dataset", frames=10, resolution="96x72")
        ds = occgt.open_dataset(cls.root, "generic")
        cls.scene_name = ds.scenes()[0]
        cls.scene = ds.scene(cls.scene_name)
        cls.ids = [f.id for f in cls.scene.frames]
        cls.tuples = [(cls.scene_name, cls.ids[0:3]), TupleRef(cls.scene_name, tuple(cls.ids[2:7]))]

    def dataset(self, **kw: object) -> TupleIndexDataset:
        return TupleIndexDataset(self.tuples, self.root, "generic", width=96, height=72,
                                 num_tracks=40, seed=3, **kw)  # type: ignore[arg-type]

    def test_query_view_and_depth_range(self) -> None:
        """query_view picks the tracks' view (as a recipe's selection.tuples.query_view), a
        given dataset_depth_range replaces the scene's: both reach views_ground_truth once
        (they used to raise TypeError, multiple values, in every item)."""
        ds = self.dataset(query_view=2, dataset_depth_range=(0.5, 4.0))
        item = ds[1]
        frames = [self.scene.load(i, 96, 72) for i in self.tuples[1].frame_ids]  # type: ignore[union-attr]
        truth = occgt.views_ground_truth(
            [f[0] for f in frames], [f[1] for f in frames], [f[2] for f in frames],
            num_tracks=40, seed=3 + 1, query_view=2, dataset_depth_range=(0.5, 4.0))
        np.testing.assert_array_equal(item["track_state"].numpy(), truth["track_state"])
        xy = truth["track_xy"]
        np.testing.assert_array_equal(item["tracks"].numpy(), np.where(np.isnan(xy), 0, xy))
        np.testing.assert_array_equal(item["point_masks"].numpy(), truth["valid"] == 1)
        # The query pixels are view 2's: its tracks sit where they started.
        state = truth["track_state"][2]
        self.assertTrue((state == occgt.TRACK_VISIBLE).all())
        self.assertFalse(np.array_equal(truth["track_xy"][0], truth["track_xy"][2]))
        # Checked here, against every tuple (tuples[0] has 3 views).
        with self.assertRaisesRegex(ValueError, r"^query_view: expected a view of every tuple, "
                                    r"got 3; tuples\[0\] has 3 views"):
            self.dataset(query_view=3)
        with self.assertRaisesRegex(ValueError, r"^query_view: expected >= 0, got -1$"):
            self.dataset(query_view=-1)
        with self.assertRaisesRegex(TypeError, r"queries"):  # not a label option
            self.dataset(queries=np.zeros((1, 2), np.int64))

    def test_item_is_the_views_ground_truth(self) -> None:
        ds = self.dataset()
        self.assertEqual(len(ds), 2)
        item = ds[1]
        ids = self.tuples[1].frame_ids  # type: ignore[union-attr]
        frames = [self.scene.load(i, 96, 72) for i in ids]
        truth = occgt.views_ground_truth(
            [f[0] for f in frames], [f[1] for f in frames], [f[2] for f in frames],
            num_tracks=40, seed=3 + 1,
            dataset_depth_range=(self.scene.min_depth_m, self.scene.max_depth_m))
        s = 5
        np.testing.assert_array_equal(item["visible_in"].numpy().view(np.uint32),
                                      truth["visible_in"])
        np.testing.assert_array_equal(item["occluded_in"].numpy().view(np.uint32),
                                      truth["occluded_in"])
        np.testing.assert_array_equal(item["track_state"].numpy(), truth["track_state"])
        np.testing.assert_array_equal(item["track_vis_mask"].numpy(),
                                      truth["track_state"] == occgt.TRACK_VISIBLE)
        xy = truth["track_xy"]
        np.testing.assert_array_equal(item["tracks"].numpy(), np.where(np.isnan(xy), 0, xy))
        self.assertEqual(tuple(item["images"].shape), (s, 3, 72, 96))
        self.assertEqual(item["images"].dtype, torch.float32)
        self.assertTrue(0 <= float(item["images"].min()) and float(item["images"].max()) <= 1)
        self.assertGreater(float(item["images"].max()), 0.2)
        self.assertEqual(tuple(item["extrinsics"].shape), (s, 3, 4))
        for k in range(s):
            T = np.eye(4)
            T[:3] = item["extrinsics"][k].numpy()
            np.testing.assert_allclose(T @ frames[k][2], np.eye(4), atol=1e-5)
            np.testing.assert_array_equal(item["depths"][k].numpy(), frames[k][0])
            np.testing.assert_allclose(item["intrinsics"][k].numpy(), frames[k][1], rtol=1e-6)
        np.testing.assert_array_equal(item["point_masks"].numpy(), truth["valid"] == 1)
        self.assertEqual(item["frame_ids"], ids)
        self.assertEqual(item["ids"].tolist(),
                         [f.number for i in ids for f in self.scene.frames if f.id == i])
        # Deterministic: the same item again.
        again = ds[1]
        self.assertTrue(torch.equal(again["tracks"], item["tracks"]))

    def test_dust3r_views(self) -> None:
        views = self.dataset(views="dust3r")[0]
        self.assertEqual(len(views), 3)
        flat = self.dataset()[0]
        for s, v in enumerate(views):
            self.assertEqual(v["instance"], self.ids[s])
            self.assertEqual(v["label"], self.scene_name)
            self.assertTrue(torch.equal(v["visible_in"], flat["visible_in"][s]))
            self.assertTrue(torch.equal(v["depthmap"], flat["depths"][s]))
            pose = v["camera_pose"].numpy()
            T = np.eye(4, dtype=np.float32)
            T[:3] = flat["extrinsics"][s].numpy()
            np.testing.assert_allclose(T @ pose, np.eye(4), atol=1e-5)
            self.assertTrue(-1 <= float(v["img"].min()) and float(v["img"].max()) <= 1)

    def test_collate_of_different_sizes(self) -> None:
        ds = self.dataset()
        batch = collate_tuples([ds[0], ds[1]])
        self.assertEqual(tuple(batch["images"].shape), (2, 5, 3, 72, 96))
        self.assertEqual(batch["view_mask"].tolist(), [[True] * 3 + [False] * 2, [True] * 5])
        self.assertEqual(tuple(batch["tracks"].shape), (2, 5, 40, 2))
        self.assertFalse(bool(batch["track_vis_mask"][0, 3:].any()))
        # Padded views' track states are TRACK_STATE_PADDED, not 0 (TRACK_VISIBLE).
        self.assertTrue(bool((batch["track_state"][0, 3:] == TRACK_STATE_PADDED).all()))
        self.assertTrue(torch.equal(batch["track_state"][0, :3], ds[0]["track_state"]))
        self.assertTrue(torch.equal(batch["visible_in"][0, :3], ds[0]["visible_in"]))
        self.assertEqual(batch["scene_id"], [self.scene_name] * 2)
        loader = torch.utils.data.DataLoader(ds, batch_size=2, collate_fn=collate_tuples)
        self.assertEqual(len(list(loader)), 1)

    def test_jsonl_and_bad_arguments(self) -> None:
        path = os.path.join(common.scratch("tuple_dataset_jsonl"), "tuples.jsonl")
        with open(path, "w") as f:
            for ids in (self.ids[0:2], self.ids[4:8]):
                f.write(json.dumps({"scene": self.scene_name, "frame_ids": ids,
                                    "covisibility": [[1.0] * len(ids)] * len(ids)}) + "\n")
        refs = read_tuples(path)
        self.assertEqual(refs[1], TupleRef(self.scene_name, tuple(self.ids[4:8])))
        self.assertEqual(len(TupleIndexDataset(path, self.root, "generic", width=96,
                                               height=72)[1]["depths"]), 4)
        with open(path, "a") as f:
            f.write('{"scene": "x"}\n')
        with self.assertRaisesRegex(ValueError, "tuples.jsonl:3: expected a tuple line"):
            read_tuples(path)
        with self.assertRaisesRegex(ValueError, "views: expected 'vggt' or 'dust3r'"):
            self.dataset(views="mast3r")
        with self.assertRaisesRegex(ValueError, r"tuples\[0\]: .*expected 2..32 frame ids"):
            TupleIndexDataset([(self.scene_name, [])], self.root, "generic")
        # One view is not a tuple (tuples_line.schema.json: 2..32), from a list or a line.
        with self.assertRaisesRegex(ValueError, r"tuples\[0\]: .*expected 2..32 frame ids, got 1"):
            TupleIndexDataset([(self.scene_name, ["000001"])], self.root, "generic")
        one = os.path.join(os.path.dirname(path), "one_view.jsonl")
        with open(one, "w") as f:
            f.write(json.dumps({"scene": self.scene_name, "frame_ids": ["000001"]}) + "\n")
        with self.assertRaisesRegex(ValueError, r"one_view.jsonl:1: .*2..32 frame ids, got 1"):
            read_tuples(one)
        # Options are checked here, as views_ground_truth resolves them, not in the first
        # worker's first item: a misspelt or pair-only option, a bad preset, a negative track
        # count or seed (item 0 failed, items >= 1 worked: seed + index), a size not an int.
        for kwargs, error, pattern in [
                ({"abs_tol": 0.1}, TypeError, r"abs_tol"),
                ({"stride": 8}, TypeError, r"stride"),
                ({"preset": "ocl"}, ValueError, r"^preset: expected one of"),
                ({"num_tracks": -1}, ValueError, r"^num_tracks: expected >= 0, got -1$"),
                ({"num_tracks": 2.7}, TypeError, r"^num_tracks: expected an int, got float$"),
                ({"seed": -1}, ValueError, r"^seed: "),
                ({"width": 96.5}, TypeError, r"^width: expected an int, got float$")]:
            with self.subTest(kwargs=kwargs), self.assertRaisesRegex(error, pattern):
                TupleIndexDataset(self.tuples, self.root, "generic", **kwargs)

    def test_seed_wraps_and_images_is_a_bool(self) -> None:
        """Item i's track seed is (seed + i) mod 2^64, the uint64 sum of `occgt tuples
        --shards` (seed=2**64-1 failed from item 1 on: "seed: expected an int in 0..2^64-1");
        images="no" was truthy, now a TypeError as in TupleShardDataset."""
        same = [self.tuples[1], self.tuples[1]]  # item 1 of `top` = item 0 of `zero`
        top = TupleIndexDataset(same, self.root, "generic", width=96, height=72,
                                num_tracks=40, seed=2**64 - 1, images=False)
        zero = TupleIndexDataset(same, self.root, "generic", width=96, height=72,
                                 num_tracks=40, seed=0, images=False)
        wrapped, first = top[1], zero[0]
        for key in ("tracks", "track_state", "visible_in"):
            self.assertTrue(torch.equal(wrapped[key], first[key]), key)
        self.assertFalse(torch.equal(wrapped["tracks"], zero[1]["tracks"]))  # seeds matter
        for images in ("no", 0, None):
            with self.subTest(images=images), self.assertRaisesRegex(
                    TypeError, r"^images: expected a bool, got " + type(images).__name__):
                self.dataset(images=images)
        self.assertNotIn("images", self.dataset(images=np.bool_(False))[0])

    def test_tuple_lines_are_typed(self) -> None:
        """scene a non-empty str, frame_ids a list of str: a str is not split into one frame
        per character, numbers are not made ids, null is not the scene 'None'; bytes that are
        not UTF-8 name the line."""
        folder = common.scratch("tuple_dataset_typed")
        scene = self.scene_name
        for line, message in [
                ({"scene": scene, "frame_ids": self.ids[1]}, "frame_ids: expected a list of str, got str"),
                ({"scene": scene, "frame_ids": [1, 2]}, "frame_ids: expected a list of str, got 1"),
                ({"scene": scene, "frame_ids": {"a": 1}}, "frame_ids: expected a list of str, got dict"),
                ({"scene": None, "frame_ids": self.ids[:2]}, "scene: expected a non-empty str, got None"),
                ({"scene": scene, "frame_ids": [self.ids[:2]]}, "frame_ids: expected a list of str"),
                # schemas/tuples_line.schema.json: uniqueItems
                ({"scene": scene, "frame_ids": [self.ids[1], self.ids[2], self.ids[1]]},
                 "frame_ids: expected distinct frame ids, '" + self.ids[1] + "' repeats")]:
            path = os.path.join(folder, "tuples.jsonl")
            with open(path, "w") as f:
                f.write(json.dumps({"scene": scene, "frame_ids": self.ids[:2]}) + "\n")
                f.write(json.dumps(line) + "\n")
            with self.subTest(line=line), self.assertRaisesRegex(
                    ValueError, "^" + path + ":2: expected a tuple line .*" + message):
                read_tuples(path)
        with open(path, "wb") as f:
            f.write(b'{"scene": "\xff", "frame_ids": []}\n')
        with self.assertRaisesRegex(ValueError, "^" + path + ":1: .*UnicodeDecodeError"):
            read_tuples(path)
        # A key given twice: json.loads would keep the second frame list silently.
        with open(path, "w") as f:
            f.write(json.dumps({"scene": scene, "frame_ids": self.ids[:2]})[:-1] +
                    ', "frame_ids": ' + json.dumps(self.ids[1:3]) + "}\n")
        with self.assertRaisesRegex(ValueError, "^" + path + ":1: expected a tuple line .*"
                                    "duplicate key 'frame_ids'"):
            read_tuples(path)
        with self.assertRaisesRegex(ValueError, r"^tuples\[1\]: expected a TupleRef or \(scene, "
                                    r"\[frame ids\]\) \(ValueError: frame_ids: expected a list of "
                                    r"str, got str\)"):
            TupleIndexDataset([(scene, self.ids[:2]), (scene, self.ids[2])], self.root, "generic")
        ds = TupleIndexDataset([(scene, np.array(self.ids[:2]))], self.root, "generic")
        self.assertEqual(ds.tuples[0], TupleRef(scene, tuple(self.ids[:2])))
        with self.assertRaisesRegex(ValueError, r"^tuples\[0\]: .*frame_ids: expected distinct "
                                    r"frame ids, '" + self.ids[0] + "' repeats"):
            TupleIndexDataset([(scene, [self.ids[0], self.ids[0]])], self.root, "generic")
        # An unknown frame names the tuple and where it came from (the line, or the list entry).
        with open(path, "w") as f:
            f.write(json.dumps({"scene": scene, "frame_ids": self.ids[:2]}) + "\n\n")
            f.write(json.dumps({"scene": scene, "frame_ids": [self.ids[0], "999999"]}) + "\n")
        ds = TupleIndexDataset(path, self.root, "generic", width=96, height=72)
        ds[0]
        with self.assertRaisesRegex(ValueError, "^tuple 1 \\(" + path + ":3\\): frame_ids: no "
                                    "frame with id '999999' in scene " + scene):
            ds[1]
        ds = TupleIndexDataset([(scene, ["999999", self.ids[0]])], self.root, "generic")
        with self.assertRaisesRegex(ValueError, r"^tuple 0 \(tuples\[0\]\): frame_ids: no frame "
                                    r"with id '999999'"):
            ds[0]
        # occgt tuples' DIR instead of DIR/tuples.jsonl: a ValueError saying which file to pass.
        with self.assertRaisesRegex(ValueError, "^" + folder + ": a folder, expected a "
                                    "tuples.jsonl file \\(pass " + path + ": the tuples of occgt "
                                    "tuples --out " + folder + "\\)$"):
            TupleIndexDataset(folder, self.root, "generic")
        with self.assertRaisesRegex(ValueError, "^" + self.root + ": a folder, expected a "
                                    "tuples.jsonl file$"):
            read_tuples(self.root)

    def test_root_and_index(self) -> None:
        """A missing root fails at construction (the readers open it lazily, so it failed in
        the first worker); an index that is not an int is a TypeError naming it."""
        with self.assertRaisesRegex(ValueError, r"^root: /no/such/root: no such dataset"):
            TupleIndexDataset(self.tuples, "/no/such/root", "generic")
        ds = self.dataset()
        with self.assertRaisesRegex(TypeError, r"^index: expected an int, got float$"):
            ds[0.5]  # type: ignore[index]

    def write_lines(self, name: str, lines: list) -> str:
        """A tuples.jsonl of ``lines`` (dicts, or "" for a blank line), as occgt tuples writes
        them (with a covisibility matrix)."""
        path = os.path.join(common.scratch(name), "tuples.jsonl")
        with open(path, "w") as f:
            for t in lines:
                if t:
                    n = len(t["frame_ids"])
                    t = {"covisibility": [[0.5] * n] * n, **t}
                f.write((json.dumps(t) if t else "") + "\n")
        return path

    def test_index_columns_are_the_lines(self) -> None:
        """read_tuples gives a TupleIndex: NumPy columns (no Python object per tuple) whose
        items are the lines' TupleRefs in order, of every size 2..32, scenes and ids shared
        between lines; slices (any step) are the list's slices and still name their lines;
        from_refs of a list gives the same items, named tuples[k]; it pickles read-only."""
        rng = np.random.default_rng(5)
        pool = [f"{i:06d}" for i in range(40)]
        lines: list = []
        for k in range(300):
            size = 2 + k % 31  # 2..32 views
            ids = [pool[i] for i in rng.permutation(len(pool))[:size].tolist()]
            lines.append({"scene": f"scene{int(rng.integers(0, 7)):02d}", "frame_ids": ids})
            if k % 50 == 7:
                lines.append("")  # blank lines are skipped, and line numbers count them
        path = self.write_lines("tuple_index_columns", lines)
        want = [TupleRef(t["scene"], tuple(t["frame_ids"])) for t in lines if t]
        want_lines = [n for n, t in enumerate(lines, 1) if t]
        index = read_tuples(path)
        self.assertIsInstance(index, TupleIndex)
        self.assertEqual(len(index), 300)
        self.assertEqual(list(index), want)
        self.assertEqual([index[k] for k in range(-300, 0)], want)
        self.assertEqual(index.scenes, list(dict.fromkeys(t.scene for t in want)))
        self.assertEqual(index.scene.dtype, np.int32)
        self.assertEqual([index.scenes[s] for s in index.scene.tolist()], [t.scene for t in want])
        self.assertEqual(sorted(index.frame_ids), pool)  # each id once
        self.assertEqual(index.frame.dtype, np.int32)
        self.assertEqual(index.offsets.dtype, np.int64)
        self.assertEqual(index.sizes.tolist(), [len(t.frame_ids) for t in want])
        self.assertEqual(index.offsets[-1], sum(len(t.frame_ids) for t in want))
        self.assertEqual(index.line.tolist(), want_lines)
        self.assertEqual([index.where(k) for k in (0, 299)],
                         [f"{path}:{want_lines[0]}", f"{path}:{want_lines[-1]}"])
        for column in (index.scene, index.frame, index.offsets, index.line):
            self.assertFalse(column.flags.writeable)
        self.assertEqual(repr(index), "TupleIndex(300 tuples in 7 scenes)")
        with self.assertRaisesRegex(IndexError, r"^index 300 out of range for 300 tuples$"):
            index[300]
        for cut in (slice(None), slice(10, 20), slice(20, 10), slice(None, None, -1),
                    slice(3, 250, 7), slice(-40, None), slice(290, 5, -13), slice(400, 500)):
            part = index[cut]
            with self.subTest(cut=cut):
                self.assertIsInstance(part, TupleIndex)
                self.assertEqual(list(part), want[cut])
                self.assertEqual(part.sizes.tolist(), [len(t.frame_ids) for t in want[cut]])
                self.assertEqual([part.where(k) for k in range(len(part))],
                                 [f"{path}:{n}" for n in want_lines[cut]])
                self.assertEqual(list(part[1::2]), want[cut][1::2])
        listed = TupleIndex.from_refs([(t.scene, list(t.frame_ids)) for t in want])
        self.assertEqual(list(listed), want)
        self.assertIsNone(listed.line)
        self.assertEqual(listed.where(5), "tuples[5]")
        again = pickle.loads(pickle.dumps(index))
        self.assertEqual(list(again), want)
        self.assertEqual(again.where(1), index.where(1))
        self.assertFalse(again.frame.flags.writeable)
        # The dataset holds the index it is given, or one of a list or a path.
        good = self.write_lines("tuple_index_dataset", [
            {"scene": self.scene_name, "frame_ids": self.ids[0:3]},
            {"scene": self.scene_name, "frame_ids": self.ids[3:5]}])
        ds = TupleIndexDataset(read_tuples(good), self.root, "generic", width=96, height=72,
                               num_tracks=40, seed=3)
        self.assertIsInstance(ds.tuples, TupleIndex)
        self.assertEqual(ds[1]["frame_ids"], tuple(self.ids[3:5]))
        self.assertIsInstance(self.dataset().tuples, TupleIndex)

    def test_index_holds_no_object_per_tuple(self) -> None:
        """The index of 5000 tuples adds a handful of objects the garbage collector tracks,
        not one or more per tuple (what a forked worker's reference counting would copy);
        a forked child reads every item of the parent's columns right."""
        lines = [{"scene": f"s{k % 13}", "frame_ids": [f"{(k + j) % 97:06d}" for j in range(8)]}
                 for k in range(5000)]
        path = self.write_lines("tuple_index_objects", lines)
        want = [TupleRef(t["scene"], tuple(t["frame_ids"])) for t in lines]
        gc.collect()
        before = len(gc.get_objects())
        index = read_tuples(path)
        gc.collect()
        self.assertLess(len(gc.get_objects()) - before, 50)
        r, w = os.pipe()
        pid = os.fork()
        if pid == 0:  # a DataLoader worker's view of the columns
            try:
                os.close(r)
                ok = all(index[k] == want[k] for k in range(len(want)))
                os.write(w, b"ok" if ok and list(index[::-1]) == want[::-1] else b"wrong")
            finally:
                os._exit(0)
        os.close(w)
        answer = os.read(r, 16)
        os.close(r)
        os.waitpid(pid, 0)
        self.assertEqual(answer, b"ok")

    def test_item_errors_name_the_line(self) -> None:
        """Errors of an item name the tuple and its file:line, also through a slice of the
        index; the query_view check over every tuple names the first short one, and the scene's
        frames are read once per process (not a dict of the whole scene per item)."""
        scene = self.scene_name
        path = self.write_lines("tuple_index_errors", [
            {"scene": scene, "frame_ids": self.ids[0:4]}, "",
            {"scene": scene, "frame_ids": self.ids[2:6]},
            {"scene": scene, "frame_ids": self.ids[6:8]},
            {"scene": scene, "frame_ids": self.ids[1:5]}, "",
            {"scene": scene, "frame_ids": [self.ids[0], "999999", self.ids[2]]},
            {"scene": scene, "frame_ids": self.ids[6:9]},
            {"scene": "nowhere", "frame_ids": self.ids[0:2]}])
        index = read_tuples(path)
        ds = TupleIndexDataset(index[3:], self.root, "generic", width=96, height=72)
        with self.assertRaisesRegex(ValueError, "^tuple 1 \\(" + path + ":7\\): frame_ids: no "
                                    "frame with id '999999' in scene " + scene + " under "):
            ds[1]
        with self.assertRaisesRegex(ValueError, "^tuple 1 \\(" + path + ":7\\): "):
            pickle.loads(pickle.dumps(ds))[1]
        with self.assertRaisesRegex(ValueError, "^tuple 0 \\(tuples\\[0\\]\\): frame_ids: no "
                                    "frame with id '999999'"):
            TupleIndexDataset(TupleIndex.from_refs([(scene, ["999999", self.ids[0]])]),
                              self.root, "generic")[0]
        with self.assertRaisesRegex(ValueError, "^tuple 3 \\(" + path + ":9\\): .*nowhere"):
            ds[3]  # the scene's own error
        for query_view, k, size in ((2, 2, 2), (3, 2, 2)):
            with self.subTest(query_view=query_view), self.assertRaisesRegex(
                    ValueError, f"^query_view: expected a view of every tuple, got {query_view}; "
                    f"tuples\\[{k}\\] has {size} views \\({scene}: {self.ids[6]}, "
                    f"{self.ids[7]}\\)$"):
                TupleIndexDataset(path, self.root, "generic", query_view=query_view)
        TupleIndexDataset(path, self.root, "generic", query_view=1)
        # After the scene's first item, its frames are not listed again.
        ds = TupleIndexDataset(index[:2], self.root, "generic", width=96, height=72,
                               images=False)
        first = ds[0]
        opened, numbers = ds._scenes[scene]

        class NoFrames:
            def __getattr__(self, name: str) -> object:
                if name == "frames":
                    raise AssertionError("the scene's frames listed again")
                return getattr(opened, name)

        ds._scenes[scene] = (NoFrames(), numbers)  # type: ignore[assignment]
        self.assertEqual(ds[1]["ids"].tolist(),
                         [f.number for i in self.ids[2:6] for f in self.scene.frames if f.id == i])
        self.assertTrue(torch.equal(ds[0]["depths"], first["depths"]))

    def test_pickle_after_use(self) -> None:
        """A dataset used in this process pickles (spawned DataLoader workers; it raised
        "cannot pickle 'occgt._occgt.Dataset' object") and gives the same items."""
        ds = self.dataset()
        first = ds[np.int64(0)]
        again = pickle.loads(pickle.dumps(ds))[0]
        for key, value in first.items():
            if isinstance(value, torch.Tensor):
                self.assertTrue(torch.equal(value, again[key]), key)

    def test_dataloader_two_workers(self) -> None:
        """Forked workers give the items of direct reads (the track seed is seed + index,
        whichever worker computes it)."""
        ds = self.dataset()
        loader = torch.utils.data.DataLoader(ds, batch_size=1, num_workers=2,
                                             collate_fn=collate_tuples)
        for index, batch in enumerate(loader):
            want = collate_tuples([ds[index]])
            for key, value in want.items():
                if isinstance(value, torch.Tensor):
                    self.assertTrue(torch.equal(batch[key], value), f"{index}: {key}")

    def test_collate_refuses_what_it_would_drop(self) -> None:
        """Items with and without images, of another view size, DUSt3R lists or pair
        samples: ValueError naming the item (the images of the second item were dropped
        when the first had none; the others raised KeyError, TypeError, RuntimeError)."""
        with_images = self.dataset()[0]
        without = self.dataset(images=False)[1]
        small = TupleIndexDataset(self.tuples, self.root, "generic", width=48, height=36,
                                  num_tracks=40, seed=3)[0]
        for batch, pattern in [
                ([without, with_images], r"^batch\[1\]: expected the keys of batch\[0\]"),
                ([with_images, without], r"^batch\[1\]: expected the keys of batch\[0\]"),
                ([with_images, small], r"^batch\[1\]: views of \(36, 48\) \(H, W\), expected "
                                       r"batch\[0\]'s \(72, 96\)"),
                ([self.dataset(views="dust3r")[0]], r"^batch\[0\]: expected a 'vggt' item .*got "
                                                     r"list \(views='dust3r'"),
                ([{"depth0": torch.zeros(2, 2)}], r"^batch\[0\]: expected a 'vggt' item .*got a "
                                                  r"dict of \['depth0'\]")]:
            with self.subTest(pattern=pattern), self.assertRaisesRegex(ValueError, pattern):
                collate_tuples(batch)  # type: ignore[arg-type]


if __name__ == "__main__":
    unittest.main()
