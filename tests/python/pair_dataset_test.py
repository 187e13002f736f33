"""occgt.torch.PairIndexDataset and occgt.torch.collate: ground truth computed on the fly from
a pair index and the dataset on disk.

- PairIndexDataset.from_split(split) gives, item by item, the arrays of the split's shards
  (every .npy member bit-equal, the grey of image0/1.png or .jpg, the options of the json), for
  the demo (PNG and JPEG images, pair, window and scene scopes) and both real samples
  (7-Scenes and TartanAir from ../shared/data; the shards are read here with tarfile, not with
  occgt's ShardDataset); its keyword arguments override any argument;
- the index readers: occgt's pairs.jsonl and selection/, occgt's LoFTR test.npz (scenes.txt),
  occgt's LoFTR train and test exports of a ScanNet-layout root mixing a ScanNet-named scene
  with another (and the export's refusal of two scenes on one LoFTR folder), LoFTR's real
  test-1500 test.npz, a scene_info folder and a list file;
- LoFTR's keys, dtypes and layouts; a DataLoader with 2 workers, shuffled, batch 4, gives the
  tensors of direct reads, in both collate layouts;
- bad indices and options raise ValueError naming the file and what was expected.
"""
from __future__ import annotations

import gzip
import io
import json
import os
import pickle
import re
import shutil
import subprocess
import sys
import tarfile
import unittest
from typing import Any, Dict, Iterator, List, Tuple

import cv2
import numpy as np
import torch
from torch.utils.data import DataLoader

sys.path.insert(0, os.path.dirname(__file__))
import common  # noqa: E402

import occgt  # noqa: E402
from occgt.torch import (Collate, PairIndex, PairIndexDataset, PairRef, collate,  # noqa: E402
                         read_pair_index)

_SPLITS: Dict[str, str] = {}

#: A build of a ScanNet-layout root with a LoFTR export of kind {kind}.
MIXED_RECIPE = """name: mixed
split: mixed
seed: 0
resolution: [320, 240]
dataset: {{format: scannet, root: {root}, min_valid_depth_fraction: 0.3}}
labels: {{preset: default}}
patches: {{stride: 8, anchor: center, mutual: true}}
selection:
  max_frame_gap: 6
  pruning: {{max_distance_m: 3.0, max_view_angle_deg: 90, frustum: true}}
  score_stride: 4
  overlap: [0.3, 0.95]
  occlusion: [0.0, 1.0]
  aggregate: mean
  quota_per_scene: 5
occupancy: {{enabled: false}}
sample: {{image: none, depth: true, labels: false, occupancy: false}}
shards: {{samples_per_shard: 8}}
loftr_export: {{kind: {kind}}}
"""


def built_split(recipe: str) -> str:
    """recipes/<recipe>.yaml built once into scratch (shared by the tests of this file)."""
    if recipe not in _SPLITS:
        out = common.scratch("pair_dataset_" + recipe)
        common.occgt("build", "--json", os.path.join(common.SOURCE, "recipes", recipe + ".yaml"), "--out",
                     out)
        _SPLITS[recipe] = out
    return _SPLITS[recipe]


def shard_samples(split: str) -> Iterator[Dict[str, bytes]]:
    """{field: bytes} of every sample of the split, in index.json order (plain tarfile)."""
    index = common.read_json(os.path.join(split, "index.json"))
    for shard in index["shardlist"]:
        sample: Dict[str, bytes] = {}
        with tarfile.open(os.path.join(split, shard["url"]), "r:") as tar:
            for member in tar:
                folder, _, base = member.name.rpartition("/")
                stem, _, field = base.partition(".")
                key = folder + "/" + stem
                if sample and sample["__key__"] != key.encode():
                    yield sample
                    sample = {}
                sample["__key__"] = key.encode()
                data = tar.extractfile(member)
                assert data is not None
                raw = data.read()
                if field.endswith(".gz"):  # sample.compression: deflate (the default)
                    field, raw = field[:-3], gzip.decompress(raw)
                sample[field] = raw
        if sample:
            yield sample


class FromSplit(unittest.TestCase):
    """Item i of from_split(split) has the arrays of the split's sample i."""

    def check_split(self, recipe: str) -> None:
        self.assertGreater(self.check_items(built_split(recipe), recipe), 0, recipe)

    def check_items(self, split: str, recipe: str) -> int:
        """Item i of from_split(split) against the split's sample i; returns how many images
        were compared."""
        ds = PairIndexDataset.from_split(split)
        samples = list(shard_samples(split))
        self.assertEqual(len(ds), len(samples), recipe)
        self.assertGreater(len(samples), 0, recipe)
        images = 0
        for i, s in enumerate(samples):
            item = ds[i]
            meta = json.loads(s["json"])
            self.assertEqual(s["__key__"].decode(), meta["key"], recipe)
            # The options the json records, the fusion's scope included (it said 'pair').
            self.assertEqual(ds.pair_options(i),
                             {k: meta[k] for k in ("label_options", "patch_options",
                                                   "occupancy_options")}, recipe)
            id0, id1 = ds.frame_ids(i)
            self.assertEqual(meta["key"], f"{item['scene_id']}/{id0}_{id1}", recipe)
            self.assertEqual(item["K0"].numpy().tolist(),
                             np.array(meta["K0"], np.float32).tolist(), recipe)
            self.assertTrue(np.allclose(item["T_0to1"].numpy(), np.array(meta["T_0to1"]),
                                        atol=1e-6), recipe)
            for c in "01":
                self.assertEqual(item["metrics" + c + ("1" if c == "0" else "0")],
                                 meta["metrics"][c + ("1" if c == "0" else "0")], recipe)
            arrays = 0
            for field, data in s.items():
                where = f"{recipe} sample {i} {field}"
                if field.endswith(".npy"):
                    want = np.load(io.BytesIO(data), allow_pickle=False)
                    got = item[field[:-4]].numpy()
                    if want.dtype == np.uint64:
                        got = got.view(np.uint64)
                    self.assertEqual(got.shape, want.shape, where)
                    self.assertTrue(np.array_equal(got.astype(want.dtype), want), where)
                    arrays += 1
                elif field in ("image0.png", "image1.png", "image0.jpg", "image1.jpg"):
                    bgr = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_COLOR)
                    grey = cv2.cvtColor(bgr, cv2.COLOR_BGR2GRAY).astype(np.float32) / 255
                    self.assertTrue(torch.equal(item["image" + field[5]], torch.from_numpy(grey[None])),
                                    where)
                    images += 1
            self.assertGreaterEqual(arrays, 7, f"{recipe} sample {i}: too few arrays compared")
        return images

    def test_demo(self) -> None:
        self.check_split("demo")

    def test_sevenscenes_sample(self) -> None:
        common.shared("sevenscenes")
        self.check_split("sevenscenes-sample")

    def test_tartanair_sample(self) -> None:
        common.shared("tartanair")
        self.check_split("tartanair-sample")


    def test_jpeg_images(self) -> None:
        """A split of sample.image: jpg: the grey images are the shards' bit for bit (the same
        JPEG bytes, decoded by OpenCV as ShardDataset does), not the colour before JPEG."""
        with open(os.path.join(common.SOURCE, "recipes", "demo.yaml")) as f:
            text = f.read()
        self.assertIn("sample: {image: png,", text)
        out = common.scratch("pair_dataset_jpeg")
        recipe = os.path.join(out, "recipe.yaml")
        with open(recipe, "w") as f:
            f.write(text.replace("sample: {image: png,", "sample: {image: jpg,")
                    .replace("quota_per_scene: 12", "quota_per_scene: 2"))
        split = os.path.join(out, "split")
        common.occgt("build", "--json", recipe, "--out", split)
        self.assertGreaterEqual(self.check_items(split, "demo jpg"), 4)
        jpeg = PairIndexDataset.from_split(split)
        self.assertEqual(jpeg.image_format, "jpg")
        lossless = PairIndexDataset.from_split(split, image_format="png")
        self.assertFalse(torch.equal(jpeg[0]["image0"], lossless[0]["image0"]))
        # encode_sample_color gives the shard's member bytes themselves.
        index = common.read_json(os.path.join(split, "index.json"))
        scene = occgt.open_dataset(os.path.join(split, "data"), "generic")
        with tarfile.open(os.path.join(split, index["shardlist"][0]["url"])) as tar:
            member = next(m for m in tar.getmembers() if m.name.endswith(".image0.jpg"))
            stored = tar.extractfile(member).read()  # type: ignore[union-attr]
            meta = json.loads(tar.extractfile(  # type: ignore[union-attr]
                member.name.replace(".image0.jpg", ".json")).read())
        rgb = scene.scene(meta["scene"]).load_color(meta["frame0"]["id"], *meta["resolution"])
        self.assertEqual(occgt._occgt.encode_sample_color(rgb, "jpg"), stored)
        for bad, pattern in ((rgb[..., :2], r"^rgb: expected uint8 \[H, W, 3\]"),
                             (rgb.astype(np.float32), r"^rgb: expected uint8")):
            with self.assertRaisesRegex(ValueError, pattern):
                occgt._occgt.encode_sample_color(bad, "jpg")
        with self.assertRaisesRegex(ValueError, r"^format: expected 'png' or 'jpg', got 'gif'$"):
            occgt._occgt.encode_sample_color(rgb, "gif")

    def test_window_and_scene_scopes(self) -> None:
        """A demo recipe whose occupancy fuses a window / the scene: from_split keeps the scope
        (Scene.fuse) and reproduces the shards' occupancy words."""
        with open(os.path.join(common.SOURCE, "recipes", "demo.yaml")) as f:
            text = f.read()
        self.assertIn("  scope: pair\n", text)
        for name, scope in (("window", "  scope: window\n  window: 1\n"),
                            ("scene", "  scope: scene\n  scene_stride: 3\n")):
            out = common.scratch("pair_dataset_scope_" + name)
            recipe = os.path.join(out, "recipe.yaml")
            with open(recipe, "w") as f:
                f.write(text.replace("  scope: pair\n", scope).replace("quota_per_scene: 12",
                                                                         "quota_per_scene: 3"))
            split = os.path.join(out, "split")
            common.occgt("build", "--json", recipe, "--out", split)
            ds = PairIndexDataset.from_split(split)
            self.assertEqual(ds.scope, {"window": "window:1", "scene": "scene:3"}[name])
            samples = list(shard_samples(split))
            self.assertEqual(len(ds), len(samples))
            for i, s in enumerate(samples):
                item = ds[i]
                # pair_options names the scope the item fuses, as the shard's json (it said
                # 'pair').
                meta = json.loads(s["json"])
                self.assertEqual(ds.pair_options(i)["occupancy_options"],
                                 meta["occupancy_options"], f"{name} sample {i}")
                for k in ("occ0", "known0", "occ1", "known1"):
                    want = np.load(io.BytesIO(s[k + ".npy"]))
                    self.assertTrue(np.array_equal(item[k].numpy().view(np.uint64), want),
                                    f"{name} sample {i} {k}")
            # Fusing the window differs from fusing the pair (else the test proves nothing).
            pair_only = PairIndexDataset.from_split(split, scope="pair")
            self.assertFalse(all(torch.equal(pair_only[i]["occ0"], ds[i]["occ0"])
                                 for i in range(len(ds))), name)


    def test_infinite_depth_limits(self) -> None:
        """A recipe's max_depth_m: .inf (no upper limit; dataset's or labels') is "inf" in
        recipe.json: from_split labels with no upper limit as the shards did (it read null as
        not given and took the reader's 50 m), and its digest differs from the recipe without
        it (they were equal, so a build into the other's folder reused its shards)."""
        with open(os.path.join(common.SOURCE, "recipes", "demo.yaml")) as f:
            text = f.read()
        self.assertIn("  min_valid_depth_fraction: 0.3\n", text)
        self.assertIn("labels:\n  preset: default\n", text)
        text = text.replace("quota_per_scene: 12", "quota_per_scene: 2")
        digests = {}
        for name, edit in (("none", ("", "")),
                           ("dataset", ("  min_valid_depth_fraction: 0.3\n",
                                        "  min_valid_depth_fraction: 0.3\n  max_depth_m: .inf\n")),
                           ("labels", ("labels:\n  preset: default\n",
                                       "labels:\n  preset: default\n"
                                       "  overrides: {max_depth_m: .inf}\n"))):
            out = common.scratch("pair_dataset_inf_" + name)
            recipe = os.path.join(out, "recipe.yaml")
            with open(recipe, "w") as f:
                f.write(text.replace(*edit))
            split = os.path.join(out, "split")
            common.occgt("build", "--json", recipe, "--out", split)
            resolved = common.read_json(os.path.join(split, "recipe.json"))
            digests[name] = resolved["options_digest"]
            if name == "none":
                continue
            section = resolved["dataset"] if name == "dataset" else resolved["labels"]["overrides"]
            self.assertEqual(section["max_depth_m"], "inf", name)
            self.check_items(split, "demo max_depth_m .inf in " + name)
            self.assertIsNone(PairIndexDataset.from_split(split).pair_options(0)
                              ["label_options"]["max_depth_m"], name)
        self.assertEqual(len(set(digests.values())), 3, digests)

    def test_overrides(self) -> None:
        """from_split's keyword arguments override any argument the recipe gives (preset,
        width and height raised "got multiple values for keyword argument")."""
        split = built_split("demo")
        first = PairIndexDataset.from_split(split).pairs[:1]
        ds = PairIndexDataset.from_split(split, preset="occ2net", width=160, height=120,
                                         stride=4, images=False, format="generic",
                                         device=occgt.DATASET_DEFAULTS["device"], pairs=first)
        self.assertEqual((len(ds), ds.preset, ds.width, ds.height, ds.images, ds.format),
                         (1, "occ2net", 160, 120, False, "generic"))
        item = ds[0]
        self.assertEqual(tuple(item["depth0"].shape), (120, 160))
        self.assertNotIn("image0", item)
        options = ds.pair_options(0)
        self.assertEqual(options["patch_options"]["stride"], 4)
        self.assertEqual(options["label_options"]["bounds"],
                         occgt.pair_options("occ2net")["label_options"]["bounds"])
        self.assertNotEqual(options["label_options"]["bounds"],
                            occgt.pair_options("default")["label_options"]["bounds"])


class Indices(unittest.TestCase):
    def test_jsonl_selection_and_loftr_export_agree(self) -> None:
        split = built_split("demo")
        from_pairs = read_pair_index(os.path.join(split, "pairs.jsonl"))
        self.assertEqual(list(read_pair_index(split)), list(from_pairs))
        with open(os.path.join(split, "pairs.jsonl"), encoding="utf-8") as f:
            lines = [json.loads(line) for line in f]
        self.assertEqual([(r.scene, r.frame0, r.frame1) for r in from_pairs],
                         [(p["scene"], p["frame0"]["id"], p["frame1"]["id"]) for p in lines])
        # selection/ holds the same pairs (scene by scene).
        os.rename(os.path.join(split, "pairs.jsonl"), os.path.join(split, "pairs.jsonl.away"))
        try:
            from_selection = read_pair_index(split)
        finally:
            os.rename(os.path.join(split, "pairs.jsonl.away"), os.path.join(split, "pairs.jsonl"))
        self.assertEqual(sorted((r.scene, r.frame0, r.frame1) for r in from_selection),
                         sorted((r.scene, r.frame0, r.frame1) for r in from_pairs))
        # occgt's LoFTR test export names scenes by number (scenes.txt) and frames by number.
        loftr = read_pair_index(os.path.join(split, "loftr", "test.npz"))
        self.assertEqual(sorted((r.scene, r.number0, r.number1) for r in loftr),
                         sorted((r.scene, r.number0, r.number1) for r in from_pairs))
        ds_loftr = PairIndexDataset(os.path.join(split, "loftr", "test.npz"),
                                    os.path.join(split, "data"), "generic", width=320, height=240)
        ds_pairs = PairIndexDataset(split, os.path.join(split, "data"), "generic", width=320,
                                    height=240)
        by_names = {ds_pairs[i]["pair_names"]: i for i in range(len(ds_pairs))}
        for i in range(len(ds_loftr)):
            a = ds_loftr[i]
            b = ds_pairs[by_names[a["pair_names"]]]
            self.assertTrue(torch.equal(a["label01"], b["label01"]))
            self.assertTrue(torch.equal(a["matches"], b["matches"]))

    def test_loftr_export_scene_names_as_written(self) -> None:
        """Scene folders ' pad ', '#hash' and 'a<tab>tab' (legal names) are lines of the export's
        scenes.txt as they are: the index names each pair's scene as pairs.jsonl does (lines
        were stripped and '#' lines skipped as comments, so rows named the next line's scene
        or ScanNet's scene0002_00); a scene name with a line break is refused by the export
        before anything is written."""
        root = common.synth_dataset("pair_dataset_names_data", frames=5, resolution="64x48")
        for old, new in (("synth_000", " pad "),):
            os.rename(os.path.join(root, old), os.path.join(root, new))
        for name in ("#hash", "a\ttab"):
            shutil.copytree(os.path.join(root, " pad "), os.path.join(root, name))
        out = common.scratch("pair_dataset_names")
        recipe = os.path.join(out, "recipe.yaml")
        with open(recipe, "w") as f:
            f.write(f"""name: names
resolution: [64, 48]
dataset: {{format: generic, root: {root}}}
selection: {{max_frame_gap: 1, score_stride: 4, pruning: {{frustum: false}}}}
occupancy: {{enabled: false}}
sample: {{image: none}}
loftr_export: {{kind: train}}
""")
        split = os.path.join(out, "split")
        common.occgt("build", recipe, "--out", split)
        with open(os.path.join(split, "pairs.jsonl")) as f:
            want = [json.loads(line)["scene"] for line in f]
        self.assertEqual(sorted(set(want)), [" pad ", "#hash", "a\ttab"])
        index = read_pair_index(os.path.join(split, "loftr", "scene_data", "train"))
        self.assertEqual(sorted(r.scene for r in index), sorted(want))
        names_file = os.path.join(split, "loftr", "scenes.txt")
        self.assertEqual(sorted(r.scene for r in read_pair_index(
            os.path.join(split, "loftr", "scene_data", "train"), names_file)), sorted(want))
        # A line break in a scene name: refused, naming the scene, before any shard.
        os.rename(os.path.join(root, "a\ttab"), os.path.join(root, "a\nb"))
        r = subprocess.run([common.BINARY, "build", recipe, "--out", os.path.join(out, "nl")],
                           capture_output=True, text=True)
        self.assertEqual(r.returncode, 1, r.stderr)
        errors = [line for line in r.stderr.splitlines() if not line.startswith("[")]
        self.assertEqual(errors, ["occgt: error: loftr export: scene a\\x0ab has a line break in "
                                  "its name, which scenes.txt (one scene name a line) cannot "
                                  "hold; rename it"])
        self.assertFalse(os.path.exists(os.path.join(out, "nl", "index.json")))

    def test_loftr_tree_with_loftr_folder_names(self) -> None:
        """occgt's own LoFTR tree (DIR/loftr/data: folders scene0000_00, ...) read with its
        test.npz: scene_names=[] names every row by LoFTR's folder, and the items are the
        split's pairs (the tree's depth is whole millimetres at 640x480, so the labels agree
        but for a few boundary pixels; scenes.txt names the build's folders, synth_000, which
        the tree does not have: that is an error naming the item and the folder)."""
        split = built_split("demo")
        index, tree = os.path.join(split, "loftr", "test.npz"), os.path.join(split, "loftr", "data")
        ds = PairIndexDataset(index, tree, "scannet", width=320, height=240, images=False,
                              scene_names=[])
        again = PairIndexDataset(split, os.path.join(split, "data"), "generic", width=320,
                                 height=240, images=False)
        self.assertEqual(len(ds), len(again))
        self.assertEqual({p.scene for p in ds.pairs}, {"scene0000_00", "scene0001_00"})
        for i in (0, len(ds) - 1):
            a, b = ds[i], again[i]
            self.assertEqual([int(n.split("/")[1]) for n in a["pair_names"]],
                             [int(n.split("/")[1]) for n in b["pair_names"]])
            agree = (a["label01"] == b["label01"]).double().mean().item()
            self.assertGreater(agree, 0.999, i)
        named = PairIndexDataset(index, tree, "scannet", width=320, height=240, images=False)
        with self.assertRaisesRegex(ValueError, r"^pair 0 \(synth_000: \d+, \d+\): " +
                                    re.escape(os.path.join(tree, "synth_000")) +
                                    r": scene folder not found$"):
            named[0]

    def test_loftr_export_of_mixed_scannet_scenes(self) -> None:
        """A ScanNet-layout root (the demo's LoFTR tree, ScanNet's exported layout) holding
        scene0707_01 and myroom, built with both LoFTR export kinds: scenes.txt lists only
        myroom (row (0, 0)); scene0707_01's rows keep (707, 1) and are read as ScanNet's
        name, so the index reads back as pairs.jsonl's pairs (it failed: "(707, 1) is not in
        the scene list"). scenes.txt is in loftr/, two folders above scene_data/{split}/ for
        kind train and beside test.npz for kind test; statistics.json keys occgt's names."""
        tree = os.path.join(built_split("demo"), "loftr", "data")
        work = common.scratch("pair_dataset_mixed")
        root = os.path.join(work, "root")
        shutil.copytree(os.path.join(tree, "scene0000_00"), os.path.join(root, "scene0707_01"))
        shutil.copytree(os.path.join(tree, "scene0001_00"), os.path.join(root, "myroom"))
        outs = {}
        for kind in ("train", "test"):
            recipe = os.path.join(work, kind + ".yaml")
            with open(recipe, "w") as f:
                f.write(MIXED_RECIPE.format(root=root, kind=kind))
            outs[kind] = os.path.join(work, kind)
            common.occgt("build", recipe, "--out", outs[kind])
        npz_root = os.path.join(outs["train"], "loftr", "scene_data", "mixed")
        for kind, index in (("train", npz_root), ("train", "mixed_list.txt"),
                            ("test", "test.npz")):
            with self.subTest(kind=kind, index=index):
                loftr = os.path.join(outs[kind], "loftr")
                self.assertEqual(common.read_bytes(os.path.join(loftr, "scenes.txt")), b"myroom\n")
                refs = read_pair_index(os.path.join(loftr, index), npz_root=npz_root)
                jsonl = read_pair_index(os.path.join(outs[kind], "pairs.jsonl"))
                self.assertEqual(sorted((r.scene, r.number0, r.number1) for r in refs),
                                 sorted((r.scene, r.number0, r.number1) for r in jsonl))
                self.assertEqual({r.scene for r in refs}, {"scene0707_01", "myroom"})
        names = np.load(os.path.join(outs["train"], "loftr", "scene_data", "mixed",
                                     "scene0707_01.npz"))["name"]
        self.assertEqual(set(map(tuple, names[:, :2].tolist())), {(707, 1)})
        self.assertFalse(os.path.exists(os.path.join(outs["train"], "loftr", "scene_data",
                                                     "mixed", "scenes.txt")))
        self.assertEqual(set(common.read_json(os.path.join(outs["test"], "loftr",
                                                           "statistics.json"))),
                         {"scene0707_01", "myroom"})
        # The same pairs through PairIndexDataset: the pair ground truth of pairs.jsonl's.
        ds = PairIndexDataset(os.path.join(outs["train"], "loftr", "mixed_list.txt"), root,
                              "scannet", width=320, height=240, images=False, npz_root=npz_root)
        again = PairIndexDataset(outs["train"], root, "scannet", width=320, height=240,
                                 images=False)
        by_names = {(again.pairs[i].scene, again.frame_ids(i)): i for i in range(len(again))}
        self.assertEqual(len(by_names), len(ds))
        for i in (0, len(ds) - 1):
            a = ds[i]
            b = again[by_names[(ds.pairs[i].scene, ds.frame_ids(i))]]
            self.assertEqual(a["pair_names"], b["pair_names"])
            self.assertTrue(torch.equal(a["matches"], b["matches"]))
        # A non-ScanNet scene whose folder scene%04d_00 is a ScanNet scene's: refused.
        clash = os.path.join(work, "clash")
        shutil.copytree(os.path.join(tree, "scene0000_00"), os.path.join(clash, "scene0000_00"))
        shutil.copytree(os.path.join(tree, "scene0001_00"), os.path.join(clash, "myroom"))
        recipe = os.path.join(work, "clash.yaml")
        with open(recipe, "w") as f:
            f.write(MIXED_RECIPE.format(root=clash, kind="train"))
        r = subprocess.run([common.BINARY, "build", recipe, "--out", os.path.join(work, "c")],
                           capture_output=True, text=True)
        self.assertEqual(r.returncode, 1, r.stderr)
        self.assertEqual(r.stderr.splitlines()[-1],
                         "occgt: error: loftr export: scenes myroom and scene0000_00 both map to "
                         "LoFTR's folder scene0000_00")
        # Refused before the write stage: no shard, index or export was written.
        written = [os.path.relpath(os.path.join(d, f), os.path.join(work, "c"))
                   for d, _, files in os.walk(os.path.join(work, "c")) for f in files]
        self.assertEqual(sorted(w for w in written if not w.startswith("selection" + os.sep)),
                         [".lock", ".tasks.lock", "recipe.json"])

    def test_loftr_test_1500(self) -> None:
        path = common.shared("loftr_scannet_test_1500/test.npz")
        refs = read_pair_index(path)
        name = np.load(path)["name"].astype(np.int64)
        self.assertEqual(len(refs), len(name))
        for r, (s, sub, n0, n1) in zip(refs, name.tolist()):
            self.assertEqual((r.scene, r.frame0, r.number0, r.number1),
                             (f"scene{s:04d}_{sub:02d}", None, n0, n1))
        scenes = sorted({r.scene for r in refs})
        self.assertEqual(len(scenes), 100)
        self.assertEqual((scenes[0], scenes[-1]), ("scene0707_00", "scene0806_00"))

    def test_scene_info_folder_and_list(self) -> None:
        out = common.scratch("pair_dataset_scene_info")
        np.savez(os.path.join(out, "scene0002_01.npz"), name=np.array([[2, 1, 30, 60]]),
                 score=np.array([0.5], np.float32))
        np.savez(os.path.join(out, "scene0001_00.npz"),
                 name=np.array([[1, 0, 0, 15], [1, 0, 15, 45]]), score=np.array([0.4, 0.7]))
        with open(os.path.join(out, "train_list.txt"), "w") as f:
            f.write("scene0002_01.npz\nscene0001_00.npz\n")
        want_sorted = [PairRef("scene0001_00", None, None, 0, 15, 0.4),
                       PairRef("scene0001_00", None, None, 15, 45, 0.7),
                       PairRef("scene0002_01", None, None, 30, 60, 0.5)]
        self.assertEqual(list(read_pair_index(out)), want_sorted)
        self.assertEqual(list(read_pair_index(os.path.join(out, "train_list.txt"))),
                         want_sorted[2:] + want_sorted[:2])
        self.assertEqual([r.scene for r in read_pair_index(os.path.join(out, "scene0001_00.npz"),
                                                           scene_names=["a", "b"])], ["b", "b"])
        # Names apply to rows (s, 0) with s < len(names); other rows are ScanNet's.
        self.assertEqual([r.scene for r in read_pair_index(out, scene_names=["a", "b"])],
                         ["b", "b", "scene0002_01"])
        np.savez(os.path.join(out, "scene0005_00.npz"), name=np.array([[5, 0, 1, 2]]))
        self.assertEqual([r.scene for r in read_pair_index(os.path.join(out, "scene0005_00.npz"),
                                                           scene_names=["a", "b"])],
                         ["scene0005_00"])

    def test_pair_index_columns(self) -> None:
        """PairIndex holds an index as NumPy columns (the paper's 230 M pairs as a list of
        PairRef took ~430 bytes a pair and were copied into every forked worker): item i,
        slices, iteration, concatenation and PairRef lists round-trip exactly, and a LoFTR
        npz costs at most 20 bytes a pair whatever its length."""
        refs = [PairRef("a", "f1", "f2", 1, 2, 0.5), PairRef("b", None, None, 7, 2**40, None),
                PairRef("a", "f2", None, None, 3, -1.25), PairRef("c", "f1", "f9")]
        index = PairIndex.from_refs(refs)
        self.assertEqual(list(index), refs)
        self.assertEqual([index[k] for k in range(-4, 4)], refs + refs)
        self.assertEqual(list(index[1:3]), refs[1:3])
        self.assertEqual(list(index[::-2]), refs[::-2])
        self.assertEqual((index.scenes, index.scene.tolist()), (["a", "b", "c"], [0, 1, 0, 2]))
        self.assertEqual(index.frame_ids, ["f1", "f2", "f9"])
        with self.assertRaisesRegex(IndexError, "pairs"):
            index[4]  # pylint: disable=pointless-statement
        with self.assertRaises(ValueError):  # the columns are shared, not to be written
            index.scene[0] = 1
        joined = PairIndex.concatenate([index, PairIndex.from_refs(refs[::-1]),
                                        PairIndex.from_refs([PairRef("d", None, None, 4, 5)])])
        self.assertEqual(list(joined), refs + refs[::-1] + [PairRef("d", None, None, 4, 5)])
        self.assertEqual(joined.scenes, ["a", "b", "c", "d"])
        with self.assertRaisesRegex(ValueError, r"pairs\[0\]: frame number 9223372036854775808 "
                                    "is not an int64"):
            PairIndex.from_refs([PairRef("a", None, None, 2**63, 1)])
        # A LoFTR npz: each row's scene as the list reader named it, numbers exact.
        out = common.scratch("pair_dataset_columns")
        rng = np.random.default_rng(3)
        n = 200_000
        name = np.stack([rng.integers(0, 40, n), rng.integers(0, 3, n),
                         rng.integers(0, 6000, n), rng.integers(0, 6000, n)], 1)
        score = rng.random(n).astype(np.float32)
        path = os.path.join(out, "big.npz")
        np.savez(path, name=name, score=score)
        names = [f"room{k}" for k in range(10)]
        big = read_pair_index(path, scene_names=names)
        self.assertEqual(len(big), n)
        columns = (big.scene, big.number0, big.number1, big.score)
        self.assertLessEqual(sum(c.nbytes for c in columns if c is not None), 16 * n)
        self.assertIsNone(big.frame_ids)
        want = [names[s] if sub == 0 and s < 10 else f"scene{s:04d}_{sub:02d}"
                for s, sub in name[:, :2].tolist()]
        self.assertEqual([big.scenes[k] for k in big.scene.tolist()], want)
        self.assertEqual(big.scenes, list(dict.fromkeys(want)))  # each once, first seen first
        self.assertEqual(big.number0.tolist(), name[:, 2].tolist())
        self.assertEqual(big.number1.tolist(), name[:, 3].tolist())
        for k in (0, 1, n // 2, n - 1):
            self.assertEqual(big[k], PairRef(want[k], None, None, int(name[k, 2]),
                                             int(name[k, 3]), float(score[k])))
        # Two (s, sub) naming one scene (scenes.txt names scene 0 as ScanNet's row (7, 1)).
        path = os.path.join(out, "alias.npz")
        np.savez(path, name=np.array([[7, 1, 0, 1], [0, 0, 2, 3]]))
        alias = read_pair_index(path, scene_names=["scene0007_01"])
        self.assertEqual((alias.scenes, alias.scene.tolist()), (["scene0007_01"], [0, 0]))

    def test_bad_indices(self) -> None:
        out = common.scratch("pair_dataset_bad")
        cases: List[Tuple[str, str]] = []
        p = os.path.join(out, "no_name.npz")
        np.savez(p, score=np.zeros(2))
        cases.append((p, "no member 'name'"))
        p = os.path.join(out, "shape.npz")
        np.savez(p, name=np.zeros((2, 3), np.int64))
        cases.append((p, "expected integers of shape [N, 4]"))
        p = os.path.join(out, "score.npz")
        np.savez(p, name=np.zeros((2, 4), np.int64), score=np.zeros(3))
        cases.append((p, "score: expected shape [2]"))
        p = os.path.join(out, "bad.jsonl")
        with open(p, "w") as f:
            f.write('{"scene": "s", "frame0": {"id": "1", "number": 1}, '
                    '"frame1": {"id": "2", "number": 2}}\n{"scene": "s"}\n')
        cases.append((p, "bad.jsonl:2: expected a pair line"))
        p = os.path.join(out, "garbage.npz")
        with open(p, "wb") as f:
            f.write(b"not a zip")
        cases.append((p, "cannot read as an npz pair index"))
        cases.append((os.path.join(out, "missing.jsonl"), "no such pair index"))
        cases.append((out, "expected pairs.jsonl, selection/*.jsonl or LoFTR *.npz"))
        for path, message in cases:
            if path == out:
                for f in os.listdir(out):
                    os.remove(os.path.join(out, f))
            with self.assertRaises(ValueError, msg=path) as e:
                read_pair_index(path)
            self.assertIn(message, str(e.exception))
            self.assertIn(os.path.basename(path), str(e.exception))

    def test_index_fields_are_typed(self) -> None:
        """pairs.jsonl fields of the wrong type (an int id, a null scene, a str number), bytes
        that are not UTF-8, a non-numeric score and negative numbers of a LoFTR npz: ValueError
        naming the file and the line or row (they passed, and failed later in pybind11 with
        its list of signatures, or with numpy's message without the file; a scene -1 became
        'scene-001_00')."""
        out = common.scratch("pair_dataset_typed")
        good = {"scene": "s", "frame0": {"id": "1", "number": 1}, "frame1": {"id": "2", "number": 2}}
        for change, message in [({"frame0": {"id": 1, "number": 1}}, "frame0.id: expected str, got 1"),
                                ({"scene": None}, "scene: expected str, got None"),
                                ({"frame1": {"id": "2", "number": "2"}},
                                 "frame1.number: expected int, got '2'"),
                                ({"frame1": {"id": "2", "number": True}},
                                 "frame1.number: expected int, got True")]:
            path = os.path.join(out, "typed.jsonl")
            with open(path, "w") as f:
                f.write(json.dumps(good) + "\n" + json.dumps({**good, **change}) + "\n")
            with self.subTest(change=change), self.assertRaisesRegex(
                    ValueError, "^" + path + ":2: expected a pair line .*" + re.escape(message)):
                read_pair_index(path)
        with open(path, "wb") as f:
            f.write(b'{"scene": "\xff"}\n')
        with self.assertRaisesRegex(ValueError, "^" + path + ":1: .*UnicodeDecodeError"):
            read_pair_index(path)
        # A key given twice, here inside frame1: json.loads would keep the second silently.
        with open(path, "w") as f:
            f.write('{"scene": "s", "frame0": {"id": "1", "number": 1}, '
                    '"frame1": {"id": "2", "number": 2, "id": "3"}}\n')
        with self.assertRaisesRegex(ValueError, "^" + path + ":1: expected a pair line .*"
                                    "duplicate key 'id'"):
            read_pair_index(path)
        path = os.path.join(out, "score.npz")
        np.savez(path, name=np.zeros((1, 4), np.int64), score=np.array(["high"]))
        with self.assertRaisesRegex(ValueError, "^" + path + r":score: expected shape \[1\] "
                                    r"\(numbers\), got <U4 \[1\]"):
            read_pair_index(path)
        path = os.path.join(out, "negative.npz")
        np.savez(path, name=np.array([[0, 0, 3, 4], [-1, 0, 3, 4]]))
        with self.assertRaisesRegex(ValueError, "^" + path + r":name\[1\]: expected scene, "
                                    r"sub-scene and frame numbers >= 0, got \[-1, 0, 3, 4\]"):
            read_pair_index(path)
        # uint64 names beyond int64 are refused (they wrapped to negative numbers; no frame
        # of a scene has such a number).
        path = os.path.join(out, "uint64.npz")
        np.savez(path, name=np.array([[1, 0, 2, 4], [2**63, 0, 2**63 + 1, 4]], np.uint64))
        with self.assertRaisesRegex(ValueError, "^" + path + r":name\[1\]: expected numbers "
                                    r"below 2\^63, got \[9223372036854775808, 0, "
                                    r"9223372036854775809, 4\]$"):
            read_pair_index(path)

    def test_refs_root_index_and_pickle(self) -> None:
        """A list of tuples instead of PairRef, a missing root (the readers open it lazily:
        it failed in the first worker) and a float index name the argument; a dataset used in
        this process pickles (spawned DataLoader workers; a scene scope's map and the
        readers raised "cannot pickle") and gives the same items."""
        split = built_split("demo")
        data = os.path.join(split, "data")
        with self.assertRaisesRegex(TypeError, r"^pairs\[0\]: expected an occgt.torch.PairRef, "
                                    r"got tuple$"):
            PairIndexDataset([("synth_000", "000000", "000001")], data, "generic")  # type: ignore
        with self.assertRaisesRegex(ValueError, r"^root: /no/such/root: no such dataset"):
            PairIndexDataset(split, "/no/such/root", "generic")
        # Options are checked here, as pair_ground_truth resolves them, not in the first
        # worker's first item (a misspelt option, a bad preset or value, a size that is not
        # an int, which was truncated: 64.9 -> 64).
        for kwargs, error, pattern in [
                ({"abs_tol": 0.1}, TypeError, r"abs_tol"),
                ({"preset": "ocl"}, ValueError, r"^preset: expected one of"),
                ({"stride": 0}, ValueError, r"stride"),
                ({"width": 0}, ValueError, r"^width, height: expected width and height in 2\.\.8192"),
                ({"width": 64.9}, TypeError, r"^width: expected an int, got float$"),
                ({"height": "48"}, TypeError, r"^height: expected an int, got str$")]:
            with self.subTest(kwargs=kwargs), self.assertRaisesRegex(error, pattern):
                PairIndexDataset(split, data, "generic", **kwargs)
        self.assertEqual(PairIndexDataset(split, data, "generic", width=np.int64(80)).width, 80)
        # A pairs.jsonl line whose frame number is another frame's than its id: an error
        # naming both (the id was used silently).
        edited = os.path.join(common.scratch("pd_number"), "pairs.jsonl")
        with open(os.path.join(split, "pairs.jsonl")) as f:
            line = json.loads(f.readline())
        line["frame0"]["number"] = line["frame1"]["number"]
        with open(edited, "w") as f:
            f.write(json.dumps(line) + "\n")
        with self.assertRaisesRegex(ValueError, r"^pair 0: frame id %s and number %d do not name "
                                    r"the same frame of scene %s \(number %d is frame %s\)$" % (
                                        line["frame0"]["id"], line["frame1"]["number"],
                                        line["scene"], line["frame1"]["number"],
                                        line["frame1"]["id"])):
            PairIndexDataset(edited, data, "generic", width=80, height=60)[0]
        ds = PairIndexDataset(split, data, "generic", width=80, height=60, occupancy="words",
                              scope="scene:4")
        with self.assertRaisesRegex(TypeError, r"^index: expected an int, got float$"):
            ds[1.0]  # type: ignore[index]
        first = ds[np.int64(1)]
        again = pickle.loads(pickle.dumps(ds))[1]
        for key, value in first.items():
            if isinstance(value, torch.Tensor):
                self.assertTrue(torch.equal(value, again[key]), key)

    def test_constructor_checks_scope_images_bins(self) -> None:
        """A bad scope (it failed in the first item; 5 gave AttributeError), images that is
        not a bool ("no" was True), an unknown image_format: TypeError / ValueError naming
        the argument at construction. bins=None is the default, as pair_options has it (it
        gave TypeError); the scope is named as Scene.fuse names it."""
        split = built_split("demo")
        data = os.path.join(split, "data")
        # The messages of occupancy::ParseFusionScope (`occgt occupancy --scope`).
        expected = r"^scope: expected pair, window:N or scene:S with N, S >= 1, got "
        for kwargs, error, pattern in [
                ({"scope": "window:x"}, ValueError, expected + "'window:x'$"),
                ({"scope": "scene:0"}, ValueError, r"^scope: N and S must be >= 1, got 'scene:0'$"),
                ({"scope": "window:-1"}, ValueError, expected + "'window:-1'$"),
                ({"scope": "window"}, ValueError,
                 r"^scope: expected pair, window:N or scene:S, got 'window'$"),
                ({"scope": 5}, TypeError, r"^scope: expected a str, got int$"),
                ({"scope": None}, TypeError, r"^scope: expected a str, got NoneType$"),
                ({"images": "no"}, TypeError, r"^images: expected a bool, got str$"),
                ({"images": 1}, TypeError, r"^images: expected a bool, got int$"),
                ({"image_format": "jpeg"}, ValueError,
                 r"^image_format: expected 'png' or 'jpg', got 'jpeg'$"),
                ({"bins": "16"}, TypeError, r"^bins: expected an int, got str$"),
                # two_point fuses nothing: a wider scope failed at the first item.
                ({"scope": "window:2", "occupancy_mode": "two_point"}, ValueError,
                 r"^scope: 'window:2' fuses frames for occupancy_mode 'octomap' only")]:
            with self.subTest(kwargs=kwargs), self.assertRaisesRegex(error, pattern):
                PairIndexDataset(split, data, "generic", width=80, height=60,
                                 occupancy="words", **kwargs)
        self.assertEqual(PairIndexDataset(split, data, "generic", occupancy="words",
                                          scope="window:01").scope, "window:1")
        for bins, depth in ((None, occgt.PAIR_DEFAULTS["bins"]), (16, 16)):
            ds = PairIndexDataset(split, data, "generic", width=80, height=60,
                                  occupancy="dense", bins=bins, images=np.bool_(False))
            self.assertEqual(ds.bins, depth)
            self.assertEqual(tuple(ds[0]["occupancy0"].shape), (depth, 30, 40))

    def test_index_of_frame_ids_and_pair_options(self) -> None:
        """frame_ids(i) and pair_options(i) check i as ds[i] does (a bare IndexError or
        TypeError came from inside); negative and numpy indices work."""
        split = built_split("demo")
        ds = PairIndexDataset(split, os.path.join(split, "data"), "generic", width=80,
                              height=60)
        n = len(ds)
        for method in (ds.frame_ids, ds.pair_options, ds.__getitem__):
            with self.subTest(method=method.__name__):
                with self.assertRaisesRegex(IndexError, rf"^index {n} out of range for {n} pairs$"):
                    method(n)
                with self.assertRaisesRegex(IndexError, rf"^index {-n - 1} out of range for "):
                    method(-n - 1)
                with self.assertRaisesRegex(TypeError, r"^index: expected an int, got float$"):
                    method(1.0)  # type: ignore[arg-type]
                with self.assertRaisesRegex(TypeError, r"^index: expected an int, got str$"):
                    method("1")  # type: ignore[arg-type]
        self.assertEqual(ds.frame_ids(-1), ds.frame_ids(n - 1))
        self.assertEqual(ds.frame_ids(np.int64(1)), ds.frame_ids(1))
        self.assertEqual(ds.pair_options(-1), ds.pair_options(n - 1))

    def test_bad_options_and_frames(self) -> None:
        split = built_split("demo")
        data = os.path.join(split, "data")
        with self.assertRaisesRegex(ValueError, "occupancy: expected None, 'words' or 'dense'"):
            PairIndexDataset(split, data, "generic", occupancy="packed")
        with self.assertRaisesRegex(ValueError, "occupancy: expected None, 'words' or 'dense'"):
            PairIndexDataset(split, data, "generic", occupancy=True)  # type: ignore[arg-type]
        with self.assertRaisesRegex(ValueError, "format"):
            PairIndexDataset(split, data, "no-such-format")
        # A scope without occupancy was ignored: nothing asked for is dropped silently.
        with self.assertRaisesRegex(ValueError, r"^scope: 'window:2' is the frames fused for "
                                    r"occupancy, which is off \(occupancy=None\)"):
            PairIndexDataset(split, data, "generic", scope="window:2")
        scene = occgt.open_dataset(data, "generic").scene("synth_000")
        with self.assertRaisesRegex(ValueError, r"^scope: 'scene:2' is the frames fused for "
                                    r"occupancy, which is off; pass occupancy=True$"):
            occgt.pair_from_scene(scene, "000000", "000001", width=80, height=60, scope="scene:2")
        ds = PairIndexDataset([PairRef("synth_000", None, None, 0, 999)], data, "generic",
                              width=320, height=240)
        with self.assertRaisesRegex(ValueError, "scene synth_000 has no frame number 999"):
            ds[0]
        with self.assertRaises(IndexError):
            ds[1]
        with self.assertRaisesRegex(ValueError, "recipe.json"):
            PairIndexDataset.from_split(data)


class LoftrKeysAndLoader(unittest.TestCase):
    @classmethod
    def setUpClass(cls) -> None:
        cls.split = built_split("sevenscenes-sample")
        cls.ds = PairIndexDataset.from_split(cls.split)

    def test_loftr_keys(self) -> None:
        s = self.ds[0]
        scene = occgt.open_dataset(common.shared("sevenscenes"), "sevenscenes").scene(s["scene_id"])
        id0, id1 = self.ds.frame_ids(0)
        self.assertEqual(s["pair_names"], (f"{s['scene_id']}/{id0}", f"{s['scene_id']}/{id1}"))
        self.assertEqual((s["dataset_name"], s["pair_id"]), ("sevenscenes", 0))
        self.assertEqual((s["image0"].dtype, tuple(s["image0"].shape)), (torch.float32, (1, 480, 640)))
        self.assertGreaterEqual(float(s["image0"].min()), 0.0)
        self.assertLessEqual(float(s["image0"].max()), 1.0)
        depth0, K0, world_from_cam0 = scene.load(id0)
        _, _, world_from_cam1 = scene.load(id1)
        self.assertTrue(torch.equal(s["depth0"], torch.from_numpy(depth0)))
        self.assertTrue(torch.equal(s["K0"], torch.from_numpy(K0.astype(np.float32))))
        T = np.linalg.inv(world_from_cam1) @ world_from_cam0
        self.assertTrue(np.allclose(s["T_0to1"].numpy(), T, atol=1e-5))
        self.assertTrue(np.allclose((s["T_1to0"] @ s["T_0to1"]).numpy(), np.eye(4), atol=1e-5))
        for k, dtype in (("matches", torch.int64), ("match_type", torch.int64),
                         ("match_xy", torch.float32), ("label01", torch.uint8),
                         ("occ0", torch.int64)):
            self.assertEqual(s[k].dtype, dtype, k)

    def test_dataloader_two_workers(self) -> None:
        direct = [self.ds[i] for i in range(len(self.ds))]
        for layout in ("pad", "concat"):
            loader = DataLoader(self.ds, batch_size=4, shuffle=True, num_workers=2,
                                collate_fn=Collate(layout),
                                generator=torch.Generator().manual_seed(3))
            seen = []
            for batch in loader:
                ids = batch["pair_id"].tolist()
                seen += ids
                for b, i in enumerate(ids):
                    want = direct[i]
                    for k in ("image0", "depth1", "K1", "T_0to1", "label01", "cells1", "occ1"):
                        self.assertTrue(torch.equal(batch[k][b], want[k]), f"{layout} {k} {i}")
                    m = want["matches"].shape[0]
                    if layout == "pad":
                        rows = batch["match_mask"][b]
                        self.assertEqual(int(rows.sum()), m)
                        self.assertTrue(bool(rows[:m].all()))
                        got = batch["matches"][b][:m]
                        self.assertFalse(bool(batch["matches"][b][m:].any()))
                    else:
                        got = batch["matches"][batch["match_b_ids"] == b]
                    self.assertTrue(torch.equal(got, want["matches"]), f"{layout} {i}")
                self.assertEqual(batch["pair_names"][0][0], direct[ids[0]]["pair_names"][0])
            self.assertEqual(sorted(seen), list(range(len(self.ds))), layout)


class CollateRules(unittest.TestCase):
    def sample(self, m: int) -> Dict[str, Any]:
        return {"x": torch.ones(2), "matches": torch.arange(2 * m).reshape(m, 2),
                "match_type": torch.zeros(m, dtype=torch.int64),
                "match_xy": torch.zeros(m, 2)}

    def test_pad_and_concat(self) -> None:
        b = collate([self.sample(3), self.sample(0), self.sample(1)])
        self.assertEqual(tuple(b["matches"].shape), (3, 3, 2))
        self.assertEqual(b["match_mask"].tolist(),
                         [[True, True, True], [False, False, False], [True, False, False]])
        self.assertEqual(tuple(b["x"].shape), (3, 2))
        c = Collate("concat")([self.sample(3), self.sample(0), self.sample(1)])
        self.assertEqual(tuple(c["matches"].shape), (4, 2))
        self.assertEqual(c["match_b_ids"].tolist(), [0, 0, 0, 2])
        empty = collate([self.sample(0), self.sample(0)])
        self.assertEqual(tuple(empty["matches"].shape), (2, 0, 2))

    def test_errors(self) -> None:
        with self.assertRaisesRegex(ValueError, "expected 'pad' or 'concat'"):
            Collate("stack")  # type: ignore[arg-type]
        with self.assertRaisesRegex(ValueError, "at least one sample"):
            collate([])
        bad = self.sample(2)
        bad["match_xy"] = torch.zeros(3, 2)
        with self.assertRaisesRegex(ValueError, r"samples\[1\]\['match_xy'\]: expected 2 rows"):
            collate([self.sample(1), bad])
        other = self.sample(1)
        del other["x"]
        with self.assertRaisesRegex(ValueError, r"samples\[1\]: expected the keys of samples\[0\]; "
                                                r"missing \['x'\], extra \[\]$"):
            collate([self.sample(1), other])
        # Tensors of other shapes: named by sample and key (was torch's bare "stack expects
        # each tensor to be equal size").
        wide = self.sample(1)
        wide["x"] = torch.ones(3)
        with self.assertRaisesRegex(ValueError, r"samples\[1\]\['x'\]: expected the shape of "
                                                r"samples\[0\] \[2\], got \[3\]"):
            collate([self.sample(1), wide])

    def test_key_order_does_not_matter(self) -> None:
        """The same keys in another order (a ShardDataset and a PairIndexDataset item in one
        ConcatDataset) batch as samples[0]'s order; they were refused."""
        a = self.sample(2)
        b = dict(reversed(list(self.sample(1).items())))
        self.assertNotEqual(list(a), list(b))
        batch = collate([a, b])
        self.assertEqual(list(batch), list(a) + ["match_mask"])
        self.assertEqual(batch["match_mask"].tolist(), [[True, True], [True, False]])


if __name__ == "__main__":
    unittest.main()
