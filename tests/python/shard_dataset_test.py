"""occgt.torch.ShardDataset against the plain tarfile reader of docs/READING_SHARDS.md.

Two small synthetic splits are built with the occgt binary (160x120, images, depth, packed
occupancy words; and one with packed + dense occupancy, no images, no depth). Every sample read
through ShardDataset, in a random order, equals the same sample read with the documented NumPy
reader (every key of the sample contract, arrays bit-equal after the contract's dtype rules); a
DataLoader with 2 worker processes, shuffled, batches of 4, occgt.torch.collate, returns the
tensors of direct reads; dense occupancy equals occgt.dense_volume of the words, the split's
own dense members and a bit-by-bit reference written here; broken folders raise ValueError
naming the file and what was expected."""
from __future__ import annotations

import gzip
import io
import json
import os
import random
import re
import shutil
import sys
import tarfile
import unittest
from typing import Any, Callable, Dict, List, Tuple

import cv2
import numpy as np
import torch
from torch.utils.data import DataLoader

sys.path.insert(0, os.path.dirname(__file__))
import common  # noqa: E402

import occgt  # noqa: E402
from occgt.torch import ShardDataset  # noqa: E402
from occgt.torch.collate import collate  # noqa: E402

RECIPE = """name: shard-dataset-test
split: {split}
seed: 0
resolution: [160, 120]
dataset:
  format: synthetic
  synthetic: {{scenes: 2, frames: 12, width: 160, height: 120, seed: 3}}
  frame_stride: 1
  min_valid_depth_fraction: 0.3
labels: {{preset: default}}
patches: {{stride: 8, anchor: center, mutual: true}}
selection:
  max_frame_gap: 4
  pruning: {{max_distance_m: 3.0, max_view_angle_deg: 90, frustum: true}}
  score_stride: 4
  overlap: [0.2, 0.98]
  occlusion: [0.0, 1.0]
  aggregate: mean
  quota_per_scene: 7
occupancy:
  enabled: true
  voxel_m: 0.1
  bins: 32
  near_m: 0.1
  far_m: 8.0
  scope: pair
  mode: octomap
  encoding: {encoding}
sample: {{image: {image}, depth: {depth}, labels: true, occupancy: true, compression: {compression}}}
shards: {{samples_per_shard: 4}}
"""

#: The keys of the sample contract (occgt/torch/__init__.py) with occupancy="words".
CONTRACT_KEYS = ["image0", "image1", "depth0", "depth1", "K0", "K1", "T_0to1", "T_1to0",
                 "dataset_name", "scene_id", "pair_id", "pair_names", "label01", "label10",
                 "cells0", "cells1", "matches", "match_type", "match_xy", "occ0", "known0",
                 "occ1", "known1", "metrics01", "metrics10"]


def build(name: str, compression: str = "none", **fields: str) -> str:
    folder = common.scratch(name)
    recipe = os.path.join(folder, "recipe.yaml")
    with open(recipe, "w") as f:
        f.write(RECIPE.format(split=name.replace("_", "-"), compression=compression, **fields))
    out = os.path.join(folder, "split")
    common.occgt("build", "--json", recipe, "--out", out)
    return out


def doc_reader() -> Dict[str, Any]:
    """The NumPy reader block of docs/READING_SHARDS.md, executed as printed."""
    with open(os.path.join(common.SOURCE, "docs", "READING_SHARDS.md")) as f:
        text = f.read()
    m = re.search(r"<!-- reader:numpy -->\s*```python\n(.*?)```\s*<!-- /reader:numpy -->", text,
                  re.S)
    assert m is not None, "docs/READING_SHARDS.md: no <!-- reader:numpy --> block"
    namespace: Dict[str, Any] = {}
    exec(compile(m.group(1), "READING_SHARDS.md:reader", "exec"), namespace)
    return namespace


def dense_reference(occ: np.ndarray, known: np.ndarray, bins: int) -> np.ndarray:
    """Bit k of the words -> bin k (0 free, 1 occupied, 255 unknown), plainly."""
    k = np.arange(bins, dtype=np.uint64)[:, None, None]
    occupied = (occ[None] >> k) & np.uint64(1)
    is_known = (known[None] >> k) & np.uint64(1)
    return np.where(is_known == 1, occupied, 255).astype(np.uint8)


def old_style_json(meta: Dict[str, Any]) -> Dict[str, Any]:
    """A sample json as occgt wrote it before the occupancy keys took occupancy.json's names:
    the bin edges as "occupancy"."bin_edges_m", the voxel size also as "occupancy"."voxel_m"
    and as "occupancy_options"."fusion"."voxel_size_m"."""
    occ, options = meta["occupancy"], meta["occupancy_options"]
    occ["bin_edges_m"] = occ.pop("bins")["edges_m"]
    occ["voxel_m"] = options["fusion"]["voxel_m"]
    options["fusion"]["voxel_size_m"] = options["fusion"].pop("voxel_m")
    return meta


def copy_split(src: str, name: str) -> str:
    dst = common.scratch(name)
    for f in os.listdir(src):
        if f.endswith((".tar", ".json", ".jsonl")):
            shutil.copy(os.path.join(src, f), dst)
    return dst


def rewrite_shard(split: str, url: str, edit: Callable[[tarfile.TarInfo, bytes], bytes]) -> None:
    """Rewrites shard `url` of a copied split with tarfile, each member's bytes through edit,
    and updates index.json's filesize."""
    tar = os.path.join(split, url)
    with tarfile.open(tar) as src:
        members = [(m, src.extractfile(m).read()) for m in src.getmembers()]  # type: ignore
    with tarfile.open(tar, "w", format=tarfile.USTAR_FORMAT) as dst:
        for m, data in members:
            data = edit(m, data)
            m.size = len(data)
            dst.addfile(m, io.BytesIO(data))
    with open(os.path.join(split, "index.json")) as f:
        index = json.load(f)
    for shard in index["shardlist"]:
        if shard["url"] == url:
            shard["filesize"] = os.path.getsize(tar)
    with open(os.path.join(split, "index.json"), "w") as f:
        json.dump(index, f)


class ShardDatasetTest(unittest.TestCase):
    full: str
    dense: str
    reader: Dict[str, Any]
    plain: List[Dict[str, Any]]
    lines: List[Dict[str, Any]]

    @classmethod
    def setUpClass(cls) -> None:
        cls.full = build("sd_full", encoding="packed", image="png", depth="true")
        cls.dense = build("sd_dense", encoding="both", image="none", depth="false")
        cls.reader = doc_reader()
        cls.plain = list(cls.reader["iter_split"](cls.full))
        with open(os.path.join(cls.full, "pairs.jsonl")) as f:
            cls.lines = [json.loads(line) for line in f]

    def expected(self, i: int) -> Dict[str, Any]:
        """Sample i of the plain reader in the contract's names, dtypes and layouts."""
        s = self.plain[i]
        meta = s["json"]
        # The contract's grey: the decoded colour through cv2's RGB -> grey weights.
        grey = [cv2.cvtColor(cv2.imdecode(np.frombuffer(s[f"image{c}.png"], np.uint8),
                                          cv2.IMREAD_COLOR), cv2.COLOR_BGR2GRAY)
                for c in "01"]
        T = np.array(meta["T_0to1"], dtype=np.float64)
        return {
            "image0": torch.from_numpy(grey[0]).float()[None] / 255,
            "image1": torch.from_numpy(grey[1]).float()[None] / 255,
            "depth0": torch.from_numpy(s["depth0.npy"]),
            "depth1": torch.from_numpy(s["depth1.npy"]),
            "K0": torch.tensor(meta["K0"], dtype=torch.float32),
            "K1": torch.tensor(meta["K1"], dtype=torch.float32),
            "T_0to1": torch.from_numpy(T.astype(np.float32)),
            "T_1to0": torch.from_numpy(np.linalg.inv(T).astype(np.float32)),
            "dataset_name": "occgt",
            "scene_id": meta["scene"],
            "pair_id": i,
            "pair_names": (meta["scene"] + "/" + meta["frame0"]["id"],
                           meta["scene"] + "/" + meta["frame1"]["id"]),
            "label01": torch.from_numpy(s["label01.npy"]),
            "label10": torch.from_numpy(s["label10.npy"]),
            "cells0": torch.from_numpy(s["cells0.npy"]),
            "cells1": torch.from_numpy(s["cells1.npy"]),
            "matches": torch.from_numpy(s["matches.npy"].astype(np.int64)),
            "match_type": torch.from_numpy(s["match_type.npy"].astype(np.int64)),
            "match_xy": torch.from_numpy(s["match_xy.npy"]),
            "occ0": torch.from_numpy(s["occ0.npy"].view(np.int64)),
            "known0": torch.from_numpy(s["known0.npy"].view(np.int64)),
            "occ1": torch.from_numpy(s["occ1.npy"].view(np.int64)),
            "known1": torch.from_numpy(s["known1.npy"].view(np.int64)),
            "metrics01": meta["metrics"]["01"],
            "metrics10": meta["metrics"]["10"],
        }

    def assert_same(self, got: Dict[str, Any], want: Dict[str, Any], where: str) -> None:
        self.assertEqual(list(got), list(want), where)
        for k, w in want.items():
            g = got[k]
            if isinstance(w, torch.Tensor):
                self.assertIsInstance(g, torch.Tensor, f"{where}: {k}")
                self.assertEqual((g.dtype, tuple(g.shape)), (w.dtype, tuple(w.shape)),
                                 f"{where}: {k}")
                self.assertTrue(torch.equal(g, w), f"{where}: {k} differs")
            else:
                self.assertEqual(g, w, f"{where}: {k}")

    def test_every_sample_equals_the_plain_reader_in_random_order(self) -> None:
        ds = ShardDataset(self.full)
        self.assertEqual(len(ds), len(self.plain))
        self.assertGreaterEqual(len(ds), 8)
        with open(os.path.join(self.full, "index.json")) as f:
            self.assertEqual(len(ds), sum(e["nsamples"] for e in json.load(f)["shardlist"]))
        order = list(range(len(ds)))
        random.Random(5).shuffle(order)
        for i in order:
            where = f"sample {i} ({self.plain[i]['__key__']})"
            got = ds[i]
            self.assertEqual(list(got), CONTRACT_KEYS, where)
            self.assert_same(got, self.expected(i), where)
            self.assertEqual(ds.key(i), self.plain[i]["__key__"], where)
            self.assertEqual(ds.pair(i), self.lines[i], where)
            self.assertTrue(got["label01"].numpy().flags.writeable, where)
        T = ds[0]["T_1to0"].double() @ ds[0]["T_0to1"].double()
        self.assertTrue(torch.allclose(T, torch.eye(4, dtype=torch.float64), atol=1e-5))
        # Python indexing: negative indices, IndexError past the end (ends iteration).
        self.assertEqual(ds[-1]["pair_id"], len(ds) - 1)
        self.assertEqual(ds.key(-len(ds)), self.plain[0]["__key__"])
        with self.assertRaises(IndexError):
            ds[len(ds)]
        self.assertEqual(sum(1 for _ in ds), len(ds))

    def test_compressed_split_reads_the_same(self) -> None:
        """sample.compression: deflate: every .npy member is stored as .npy.gz (gzip, level 1);
        ShardDataset returns the same tensors as from the plain split, `occgt validate` and the
        C++ readers (inspect split's gallery) accept it, and it is much smaller."""
        z = build("sd_deflate", compression="deflate", encoding="packed", image="png",
                  depth="true")
        def member_fields(split: str) -> set:
            names = set()
            for shard in sorted(f for f in os.listdir(split) if f.endswith(".tar")):
                with tarfile.open(os.path.join(split, shard)) as tf:
                    names.update(m.name.split(".", 1)[1] for m in tf if m.isfile())
            return names

        plain_names = member_fields(self.full)  # compression: none in its recipe
        self.assertIn("label01.npy", plain_names)
        self.assertNotIn("label01.npy.gz", plain_names)
        names = member_fields(z)
        self.assertIn("label01.npy.gz", names)
        self.assertIn("occ0.npy.gz", names)
        self.assertNotIn("label01.npy", names)
        self.assertIn("image0.png", names)  # images stay as they are
        size = lambda d: sum(os.path.getsize(os.path.join(d, f))  # noqa: E731
                             for f in os.listdir(d) if f.endswith(".tar"))
        self.assertLess(size(z), 0.5 * size(self.full))
        plain, packed = ShardDataset(self.full), ShardDataset(z)
        self.assertEqual(len(plain), len(packed))
        for i in range(len(plain)):
            self.assert_same(packed[i], plain[i], f"compressed sample {i}")
        r = common.occgt("validate", z)
        self.assertIn("valid", r.stdout)
        common.occgt("inspect", "split", z, "--out", os.path.join(z, "inspect"), "--gallery", "2")
        with open(os.path.join(z, "inspect", "report.html"), encoding="utf-8") as f:
            self.assertNotIn("could not be read", f.read())
        # docs/READING_SHARDS.md's NumPy reader: the same fields and arrays.
        for got, want in zip(self.reader["iter_split"](z), self.plain):
            self.assertEqual(sorted(got), sorted(want))
            for field, value in want.items():
                if isinstance(value, np.ndarray):
                    self.assertTrue(np.array_equal(got[field], value), field)
        # occgt eval's streaming reader: the same scores on both splits.
        sys.path.insert(0, os.path.join(common.SOURCE, "tests", "eval"))
        import predictions  # noqa: E402
        arrays = {}
        for sample in predictions.iter_samples(self.full):
            k0, k1, _ = predictions.truth_matches(sample)
            arrays[sample["__key__"] + "/kpts0"] = k0
            arrays[sample["__key__"] + "/kpts1"] = k1
        npz = os.path.join(z, "..", "gt_matches.npz")
        np.savez(npz, **arrays)
        docs = []
        for split in (self.full, z):
            out = os.path.join(z, "..", os.path.basename(os.path.dirname(split)) + "_eval.json")
            common.occgt("eval", split, "--predictions", "gt=" + npz, "--out", out)
            with open(out) as f:
                doc = json.load(f)
            docs.append((doc["sets"][0]["overall"], doc["pairs"], doc["match_quality"]))
        self.assertEqual(docs[0], docs[1])
        self.assertTrue(docs[1][2]["available"])
        # A member that is not gzip: one clear error from the reader.
        bad = copy_split(z, "sd_deflate_bad")
        shard = os.path.join(bad, sorted(f for f in os.listdir(bad) if f.endswith(".tar"))[0])
        with tarfile.open(shard) as tf:
            at = next(m.offset_data for m in tf if m.name.endswith("label01.npy.gz"))
        with open(shard, "r+b") as f:  # the first member's gzip bytes, same size
            f.seek(at)
            f.write(b"not gzip at all!")
        with self.assertRaisesRegex(ValueError, r"label01\.npy\.gz: not gzip data"):
            ShardDataset(bad)[0]
        # A corrupt body and a trailer that lies about the size: one clear error each.
        member = next(m for m in tarfile.open(os.path.join(z, os.path.basename(shard)))
                      if m.name.endswith("label01.npy.gz"))
        for offset, patch, message in [(member.size // 2, b"\xff\x00\xff\x00", "bad gzip data"),
                                       (member.size - 4, b"\xff\xff\xff\x7f", "bad gzip data"),
                                       (member.size - 4, b"\x01\x00\x00\x00",
                                        "inflates to more than 1 bytes|bad gzip data")]:
            shutil.copyfile(os.path.join(z, os.path.basename(shard)), shard)
            with open(shard, "r+b") as f:
                f.seek(at + offset)
                f.write(patch)
            with self.subTest(offset=offset), \
                    self.assertRaisesRegex(ValueError, r"label01\.npy\.gz: .*(" + message + ")"):
                ShardDataset(bad)[0]

    def test_compressed_npy_inflates_only_to_its_header_size(self) -> None:
        # A member whose gzip stream runs 64 MiB past the array its .npy header declares is
        # refused at the header's size (it used to inflate up to the trailer's 4 GiB).
        from occgt._occgt import gunzip_npy
        buf = io.BytesIO()
        np.save(buf, np.arange(4, dtype=np.float32))
        npy = buf.getvalue()
        self.assertEqual(bytes(gunzip_npy(gzip.compress(npy), "k.depth0.npy.gz")), npy)
        bomb = gzip.compress(npy + bytes(64 << 20), 9)
        self.assertLess(len(bomb), 1 << 20)
        with self.assertRaisesRegex(ValueError, rf"k\.depth0\.npy\.gz: gzip data inflates to "
                                    rf"more than {len(npy)} bytes"):
            gunzip_npy(bomb, "k.depth0.npy.gz")

    def test_color_and_options(self) -> None:
        ds = ShardDataset(self.full, color=True, depth=False, occupancy="none")
        s = ds[3]
        for c in "01":
            bgr = cv2.imdecode(np.frombuffer(self.plain[3][f"image{c}.png"], np.uint8),
                               cv2.IMREAD_COLOR)
            want = torch.from_numpy(np.ascontiguousarray(bgr[:, :, ::-1].transpose(2, 0, 1)))
            self.assertEqual(s["color" + c].dtype, torch.uint8)
            self.assertTrue(torch.equal(s["color" + c], want), "color" + c)
        self.assertTrue(torch.equal(s["image0"], self.expected(3)["image0"]))
        for k in ("depth0", "occ0", "known1", "occupancy0"):
            self.assertNotIn(k, s)
        s = ShardDataset(self.full, images=False, labels=False, dataset_name="ScanNet")[2]
        for k in ("image0", "label01", "cells1"):
            self.assertNotIn(k, s)
        self.assertEqual(s["dataset_name"], "ScanNet")
        with self.assertRaisesRegex(ValueError, r"occupancy: expected one of words, dense, none"):
            ShardDataset(self.full, occupancy="packed")

    def test_dataloader_two_workers_shuffled(self) -> None:
        ds = ShardDataset(self.full)
        ds[0]  # files opened in the parent before the fork: workers must reopen their own
        torch.manual_seed(11)
        loader = DataLoader(ds, batch_size=4, shuffle=True, num_workers=2, collate_fn=collate)
        seen: List[int] = []
        for batch in loader:
            ids = batch["pair_id"].tolist()
            seen += ids
            for b, i in enumerate(ids):
                want = ds[i]
                where = f"batch sample {b} (pair {i})"
                rows = int(batch["match_mask"][b].sum())
                self.assertEqual(rows, want["matches"].shape[0], where)
                for k, w in want.items():
                    if k in ("matches", "match_type", "match_xy"):
                        self.assertTrue(torch.equal(batch[k][b, :rows], w), f"{where}: {k}")
                    elif isinstance(w, torch.Tensor):
                        self.assertTrue(torch.equal(batch[k][b], w), f"{where}: {k}")
                self.assertEqual(batch["scene_id"][b], want["scene_id"], where)
                self.assertEqual((batch["pair_names"][0][b], batch["pair_names"][1][b]),
                                 want["pair_names"], where)
                self.assertEqual(batch["metrics01"]["overlap"][b].item(),
                                 want["metrics01"]["overlap"], where)
        self.assertEqual(sorted(seen), list(range(len(ds))))
        self.assertNotEqual(seen, list(range(len(ds))), "shuffle=True gave the identity order")

    def test_pair_names_key_predictions_for_eval(self) -> None:
        """A LoFTR-style test loop keys its matches by '#'.join(pair_names) (docs/EVAL.md);
        `occgt eval` takes the names this dataset gives, each the pair of its sample."""
        ds = ShardDataset(self.full, depth=False)
        loader = DataLoader(ds, batch_size=3, shuffle=False, num_workers=0, collate_fn=collate)
        arrays: Dict[str, np.ndarray] = {}
        for batch in loader:
            for b, (name0, name1) in enumerate(zip(*batch["pair_names"])):
                rows = int(batch["match_mask"][b].sum())
                xy = batch["match_xy"][b, :rows].numpy().astype(np.float32)
                cells = batch["matches"][b, :rows, 0].numpy()
                width = 160 // 8
                kpts0 = np.stack([(cells % width) * 8 + 3.5, (cells // width) * 8 + 3.5], 1)
                arrays[name0 + "#" + name1 + "/kpts0"] = kpts0.astype(np.float32)
                arrays[name0 + "#" + name1 + "/kpts1"] = xy
        self.assertEqual(len(arrays), 2 * len(ds))
        path = os.path.join(common.scratch("shard_dataset_eval"), "by_pair_names.npz")
        np.savez(path, **arrays)
        out = path[:-4] + ".json"
        common.occgt("eval", self.full, "--predictions", path, "--out", out)
        with open(out) as f:
            overall = json.load(f)["sets"][0]
        self.assertEqual(overall["pairs_missing"], 0)
        self.assertEqual(overall["overall"]["pairs"], len(ds))
        # Each sample's ground-truth matches (from its cell centres) scored against its own
        # pair: nearly all visible-visible ones correct (a pair taken for another: near 0).
        self.assertGreater(overall["overall"]["types"]["vv"]["precision_percent"], 90.0)

    def test_dense_occupancy(self) -> None:
        # Words only in the split: unpacked by occgt.dense_volume (C++).
        ds = ShardDataset(self.full, occupancy="dense")
        bins = len(self.plain[0]["json"]["occupancy"]["bins"]["edges_m"]) - 1
        self.assertEqual(bins, 32)
        for i in (0, len(ds) - 1):
            s, p = ds[i], self.plain[i]
            self.assertNotIn("occ0", s)
            for c in "01":
                occ, known = p[f"occ{c}.npy"], p[f"known{c}.npy"]
                want = occgt.dense_volume(occ, known, bins)
                got = s["occupancy" + c]
                self.assertEqual((got.dtype, tuple(got.shape)),
                                 (torch.uint8, (bins,) + occ.shape), f"{i}: occupancy{c}")
                self.assertTrue(np.array_equal(got.numpy(), want), f"{i}: occupancy{c}")
                self.assertTrue(np.array_equal(want, dense_reference(occ, known, bins)))
                self.assertTrue((got == 1).any() and (got == 0).any() and (got == 255).any())
        # A split storing both encodings: its dense members, equal to the unpacked words.
        plain = list(self.reader["iter_split"](self.dense))
        ds = ShardDataset(self.dense, occupancy="dense", images=False, depth=False)
        words = ShardDataset(self.dense, occupancy="words", images=False, depth=False)
        self.assertEqual(len(ds), len(plain))
        for i in range(len(ds)):
            s, w, p = ds[i], words[i], plain[i]
            for c in "01":
                self.assertTrue(np.array_equal(s["occupancy" + c].numpy(), p[f"occ{c}_dense.npy"]))
                self.assertTrue(np.array_equal(
                    s["occupancy" + c].numpy(),
                    occgt.dense_volume(w["occ" + c].numpy().view(np.uint64),
                                       w["known" + c].numpy().view(np.uint64), bins)))

    def test_samples_written_before_the_occupancy_renames(self) -> None:
        """A split whose sample jsons have the old occupancy keys (bin_edges_m, voxel_size_m)
        reads as the split itself (dense volumes need the number of bins)."""
        old = copy_split(self.full, "sd_old_keys")
        with open(os.path.join(old, "index.json")) as f:
            index = json.load(f)
        for shard in index["shardlist"]:
            tar = os.path.join(old, shard["url"])
            with tarfile.open(tar) as src:
                members = [(m, src.extractfile(m).read()) for m in src.getmembers()]
            with tarfile.open(tar, "w", format=tarfile.USTAR_FORMAT) as dst:
                for m, data in members:
                    if m.name.endswith(".json"):
                        meta = json.loads(data)
                        self.assertNotIn("bin_edges_m", meta["occupancy"])
                        self.assertNotIn("voxel_m", meta["occupancy"])
                        data = json.dumps(old_style_json(meta)).encode()
                        m.size = len(data)
                    dst.addfile(m, io.BytesIO(data))
            shard["filesize"] = os.path.getsize(tar)
        with open(os.path.join(old, "index.json"), "w") as f:
            json.dump(index, f)
        self.assertEqual(self.plain[0]["json"]["occupancy_options"]["fusion"]["voxel_m"], 0.1)
        for occupancy in ("dense", "words"):
            new_ds = ShardDataset(self.full, occupancy=occupancy)
            old_ds = ShardDataset(old, occupancy=occupancy)
            self.assertEqual(len(old_ds), len(new_ds))
            for i in range(len(new_ds)):
                self.assert_same(old_ds[i], new_ds[i], f"old-style sample {i}, {occupancy}")

    def test_npy_members(self) -> None:
        """The in-place .npy parser: numpy.save's headers (the matched form), any other valid
        header (literal_eval), Fortran order, empty and 0-d arrays; bad ones raise."""
        from occgt.torch.shards import _npy

        arrays = [np.arange(12, dtype=np.uint64).reshape(3, 4), np.arange(5, dtype=np.uint8),
                  np.asfortranarray(np.arange(24, dtype=">f4").reshape(2, 3, 4)),
                  np.array(7, dtype=np.int32), np.zeros((0, 2), np.int32)]
        for a in arrays:
            data = bytearray(b"pad" + common.npy_bytes(a))
            got = _npy(data, 3, len(data) - 3, "x")
            self.assertEqual((got.dtype, got.shape), (a.dtype, a.shape))
            self.assertTrue(np.array_equal(got, a))
        header = b"{'shape': (2, 2), 'descr': '<i2', 'fortran_order': False}"
        header += b" " * (63 - len(header)) + b"\n"
        data = bytearray(b"\x93NUMPY\x01\x00" + len(header).to_bytes(2, "little") + header +
                         np.array([[1, 2], [3, 4]], "<i2").tobytes())
        self.assertTrue(np.array_equal(_npy(data, 0, len(data), "x"), [[1, 2], [3, 4]]))
        with self.assertRaisesRegex(ValueError, r"x: \(2, 2\) int16 needs 8 bytes, the member "
                                                r"holds 6"):
            _npy(data, 0, len(data) - 2, "x")
        with self.assertRaisesRegex(ValueError, r"x: expected a plain dtype, got object"):
            _npy(bytearray(data.replace(b"'<i2'", b"'|O8'")), 0, len(data), "x")
        with self.assertRaisesRegex(ValueError, r"x: bad .npy header"):
            _npy(bytearray(data.replace(b"'shape'", b"'shope'")), 0, len(data), "x")
        with self.assertRaisesRegex(ValueError, r"x: expected a .npy file"):
            _npy(bytearray(b"PK\x03\x04" + bytes(20)), 0, 24, "x")

    def test_kept_tensors_do_not_hold_the_sample_buffer(self) -> None:
        """On a split of uncompressed members, no tensor of an item lies in the buffer of the
        sample's one read: a view (np.frombuffer) kept every member's bytes alive as long as
        any tensor was kept (+300 MB for 192 kept cells0 of the demo)."""
        import ctypes

        ds = ShardDataset(self.full, depth=True, color=True)  # compression: none
        buffers: List[Tuple[int, int]] = []
        read_raw = ds.read_raw

        def recording_read_raw(i: int) -> Any:
            buf, members = read_raw(i)
            start = ctypes.addressof((ctypes.c_char * len(buf)).from_buffer(buf))
            buffers.append((start, start + len(buf)))
            return buf, members

        ds.read_raw = recording_read_raw  # type: ignore[method-assign]
        item = ds[1]
        self.assertEqual(len(buffers), 1)
        lo, hi = buffers[0]
        checked = 0
        for k, t in item.items():
            if isinstance(t, torch.Tensor) and t.numel() > 0:
                p = t.data_ptr()
                self.assertFalse(lo <= p < hi, f"{k} lies in the sample's buffer")
                checked += 1
        self.assertGreaterEqual(checked, 10)

    def test_member_ranges_come_from_the_cpp_reader(self) -> None:
        """The byte ranges are the C++ shard reader's (occgt._occgt.shard_samples: libgt/shards,
        libarchive): every member read through them is tarfile's, also in tarfile-written pax
        and GNU archives (long-name records before a header); a shard with a damaged header
        or cut inside a member raises ValueError naming the shard and the header or member."""
        from occgt._occgt import shard_samples

        ds = ShardDataset(self.full)
        with open(os.path.join(self.full, "index.json")) as f:
            urls = [e["url"] for e in json.load(f)["shardlist"]]
        i = 0
        for url in urls:
            with tarfile.open(os.path.join(self.full, url)) as tf:
                members = [m for m in tf if m.isfile()]
                for key in dict.fromkeys(m.name.split(".", 1)[0] for m in members):
                    want = {m.name.split(".", 1)[1]: m for m in members
                            if m.name.split(".", 1)[0] == key}
                    buf, ranges = ds.read_raw(i)
                    self.assertEqual(ds.key(i), key)
                    self.assertEqual(list(ranges), list(want), key)
                    for field, (offset, size) in ranges.items():
                        extracted = tf.extractfile(want[field])
                        assert extracted is not None
                        self.assertEqual(bytes(buf[offset:offset + size]), extracted.read(),
                                         f"{key}.{field}")
                    i += 1
        self.assertEqual(i, len(ds))

        folder = common.scratch("sd_pax_gnu")
        long_key = "scene/" + "k" * 120 + "/000001_000002"
        for fmt in (tarfile.PAX_FORMAT, tarfile.GNU_FORMAT):
            path = os.path.join(folder, f"format{fmt}.tar")
            with tarfile.open(path, "w", format=fmt) as tf:
                for name, data in [("s/0_1.json", b"{}"), (long_key + ".json", b"[1]"),
                                   (long_key + ".depth0.npy", bytes(range(256)) * 5),
                                   ("s/2_3.json", b"[]")]:
                    info = tarfile.TarInfo(name)
                    info.size = len(data)
                    tf.addfile(info, io.BytesIO(data))
            with tarfile.open(path) as tf:
                tar_ranges = [(m.name, m.offset_data, m.size) for m in tf]
            listed = [(key + "." + field, start + offset, size)
                      for key, start, _, fields in shard_samples(path)
                      for field, (offset, size) in fields.items()]
            self.assertEqual(listed, tar_ranges, f"format {fmt}")

        damaged = copy_split(self.full, "sd_damaged_header")
        tar = os.path.join(damaged, urls[-1])
        with tarfile.open(tar) as tf:
            before, third = list(tf)[1:3]
        with open(tar, "r+b") as f:
            f.seek(third.offset + 3)
            byte = f.read(1)
            f.seek(third.offset + 3)
            f.write(bytes([byte[0] ^ 1]))
        with self.assertRaisesRegex(ValueError, re.escape(
                f"{tar}: tar header at byte {third.offset} (after member {before.name}): "
                f"checksum mismatch")):
            ShardDataset(damaged)

        cut = copy_split(self.full, "sd_cut_member")
        tar = os.path.join(cut, urls[0])
        with tarfile.open(tar) as tf:
            member = [m for m in tf if m.size > 1000][-1]
        os.truncate(tar, member.offset_data + 1000)
        with open(os.path.join(cut, "index.json")) as f:
            index = json.load(f)
        index["shardlist"][0]["filesize"] = os.path.getsize(tar)
        with open(os.path.join(cut, "index.json"), "w") as f:
            json.dump(index, f)
        with self.assertRaisesRegex(ValueError, re.escape(
                f"{tar}: {member.name}: member of {member.size} bytes at byte "
                f"{member.offset_data} runs past the end of the file")):
            ShardDataset(cut)

    def test_members_are_checked_against_the_contract(self) -> None:
        """A sample whose .npy members or json do not hold what the contract says (a member of
        another dtype or shape, a T_0to1 that is singular or not finite) raises ValueError
        naming the member when read; before, they were returned as they were (a float64
        label map, a match_type of another length than matches) or raised numpy's
        LinAlgError without a file name."""
        url = "sd-full-000000.tar"
        first = self.plain[0]["__key__"]
        singular = json.dumps({**self.plain[0]["json"], "T_0to1": np.zeros((4, 4)).tolist()})
        nan_T = json.dumps({**self.plain[0]["json"],
                            "T_0to1": np.full((4, 4), np.nan).tolist()})
        # Rigid within pair_ground_truth's 1e-3 (was |det R - 1| <= 0.1: a 5 % scale passed).
        scaled = np.array(self.plain[0]["json"]["T_0to1"])
        scaled[:3, :3] = scaled[:3, :3] @ np.diag([1, 1, 1.05])
        scaled_T = json.dumps({**self.plain[0]["json"], "T_0to1": scaled.tolist()})
        bad_K = json.dumps({**self.plain[0]["json"],
                            "K0": [[-1.0, 0, 0], [0, -1.0, 0], [0, 0, 0]]})
        label9 = self.plain[0]["label01.npy"].copy()
        label9[0, 3] = 9
        nan_depth = self.plain[0]["depth1.npy"].copy()
        nan_depth[1, 0] = np.nan
        moved_xy = self.plain[0]["match_xy.npy"].copy()
        moved_xy[0, 0] += 8  # one cell to the right (or off the grid)
        cases = [
            ("label01.npy", common.npy_bytes(self.plain[0]["label01.npy"].astype(np.float64)),
             r"label01\.npy: expected uint8 \[120, 160\] \(sample resolution 160x120\), got "
             r"float64 \[120, 160\]"),
            ("depth0.npy", common.npy_bytes(np.zeros((12, 16), np.float32)),
             r"depth0\.npy: expected float32 \[120, 160\] .*got float32 \[12, 16\]"),
            ("match_type.npy", common.npy_bytes(np.zeros(1, np.uint8)),
             r"match_type\.npy: expected uint8 \[%d\] .*got uint8 \[1\]"
             % len(self.plain[0]["matches.npy"])),
            ("matches.npy", common.npy_bytes(self.plain[0]["matches.npy"].astype(np.float32)),
             r"matches\.npy: expected int32 \[\*, 2\] .*got float32"),
            ("occ0.npy", common.npy_bytes(self.plain[0]["occ0.npy"].view(np.int64)),
             r"occ0\.npy: expected uint64 \[60, 80\] .*got int64 \[60, 80\]"),
            # A cell index outside the grid, a type outside 0..2 (was passed through).
            ("matches.npy", common.npy_bytes(np.where(
                np.arange(self.plain[0]["matches.npy"].size).reshape(-1, 2) == 1, 10 ** 6,
                self.plain[0]["matches.npy"]).astype(np.int32)),
             r"matches\.npy: row 0 names cell 1000000 of image 1, which has 300 cells "
             r"\(160x120, stride 8\)"),
            ("match_type.npy", common.npy_bytes(np.full(len(self.plain[0]["matches.npy"]), 5,
                                                        np.uint8)),
             r"match_type\.npy: row 0 is 5; expected 0 \(vv\), 1 \(vo\) or 2 \(ov\)"),
            ("json", singular.encode(), r"json: T_0to1: last row of the pose is not "
                                        r"\[0 0 0 1\]"),
            # NaN is not a JSON token (Python's json writes it; no JSON reader takes it).
            ("json", nan_T.encode(), r"json: not valid JSON"),
            ("json", scaled_T.encode(), r"json: T_0to1: rotation is not orthonormal"),
            ("json", bad_K.encode(), r"json: K0: expected \[\[fx, 0, cx\]"),
            # Values against the json and each other (shards::CheckPairSampleValues): a label
            # code past 5 and a NaN depth reached the trainer before.
            ("label01.npy", common.npy_bytes(label9),
             r"label01\.npy: pixel \(3, 0\) holds 9; expected a label code 0\.\.5"),
            ("depth1.npy", common.npy_bytes(nan_depth),
             r"depth1\.npy: pixel \(0, 1\) holds nan; expected metres >= 0 \(0 = invalid\)"),
            ("match_xy.npy", common.npy_bytes(moved_xy),
             r"match_xy\.npy: row 0 \(.*\) lies in cell .* of image 1, matches\.npy says "),
        ]
        for field, data, pattern in cases:
            split = copy_split(self.full, "sd_contract")
            rewrite_shard(split, url, lambda m, d: data if m.name == f"{first}.{field}" else d)
            ds = ShardDataset(split)
            with self.subTest(field=field, pattern=pattern):
                with self.assertRaisesRegex(ValueError, "^" + re.escape(
                        f"{os.path.join(split, url)}: {first}.") + pattern):
                    ds[0]
                self.assertEqual(ds[1]["pair_id"], 1)  # the other samples read
        # A pairs.jsonl line that is not JSON: ValueError naming the line (was json's
        # JSONDecodeError without the file).
        split = copy_split(self.full, "sd_contract")
        with open(os.path.join(split, "pairs.jsonl"), "r+b") as f:
            lines = f.read().split(b"\n")
            lines[1] = b"{\xff" + lines[1][2:]
            f.seek(0)
            f.write(b"\n".join(lines))
        ds = ShardDataset(split)
        self.assertEqual(ds.pair(0), self.lines[0])
        with self.assertRaisesRegex(ValueError, "^" + re.escape(os.path.join(split, "pairs.jsonl")) +
                                    r": line 2: expected a JSON object with key"):
            ds.pair(1)
        ds = ShardDataset(self.full)
        with self.assertRaisesRegex(TypeError, r"^sample index: expected an int, got float$"):
            ds[1.5]  # type: ignore[index]
        with self.assertRaisesRegex(TypeError, r"^sample index: expected an int, got bool$"):
            ds[True]  # was item 1
        self.assertEqual(ds[np.int64(2)]["pair_id"], 2)
        self.assertEqual(ds[torch.tensor(3)]["pair_id"], 3)  # type: ignore[index]
        # Flags are bools and the name a str, as TupleShardDataset's ("no" was truthy).
        for kwargs, pattern in [({"images": "no"}, r"^images: expected a bool, got str$"),
                                ({"labels": 0}, r"^labels: expected a bool, got int$"),
                                ({"dataset_name": 5}, r"^dataset_name: expected a str, got int$")]:
            with self.subTest(kwargs=kwargs), self.assertRaisesRegex(TypeError, pattern):
                ShardDataset(self.full, **kwargs)  # type: ignore[arg-type]

    def test_dense_only_compressed_split(self) -> None:
        """occupancy encoding: dense with sample.compression: deflate (the default) stores
        only occ0_dense.npy.gz: occupancy="dense" reads it (it looked for occ0_dense.npy,
        fell back to the words the split does not have, and raised KeyError 'occ0.npy.gz')."""
        z = build("sd_dense_gz", compression="deflate", encoding="dense", image="none",
                  depth="false")
        ds = ShardDataset(z, occupancy="dense", images=False, depth=False)
        both = ShardDataset(self.dense, occupancy="dense", images=False, depth=False)
        self.assertEqual([ds.key(i) for i in range(len(ds))],
                         [both.key(i) for i in range(len(both))])
        for i in range(len(ds)):
            for c in "01":
                self.assertTrue(torch.equal(ds[i]["occupancy" + c], both[i]["occupancy" + c]))
        with self.assertRaisesRegex(ValueError, r"has no occ0\.npy member \(asked for by "
                                    r"occupancy='words'\)"):
            ShardDataset(z, occupancy="words", images=False, depth=False)
        # Unset: the dense volumes the split stores.
        self.assertEqual(ShardDataset(z).occupancy, "dense")

    def test_views_split_is_named(self) -> None:
        """An N-view split (occgt tuples --shards) is refused as such, not as a pair sample
        without matches.npy."""
        folder = common.scratch("sd_views")
        tar = os.path.join(folder, "v-000000.tar")
        with tarfile.open(tar, "w", format=tarfile.USTAR_FORMAT) as tf:
            for name, data in [("s/tuple_000000.json", b"{}"),
                               ("s/tuple_000000.visible_in.npy.gz", b"x")]:
                info = tarfile.TarInfo(name)
                info.size = len(data)
                tf.addfile(info, io.BytesIO(data))
        with open(os.path.join(folder, "index.json"), "w") as f:
            json.dump({"__kind__": "wids-shard-index-v1",
                       "shardlist": [{"url": "v-000000.tar", "nsamples": 1,
                                      "filesize": os.path.getsize(tar)}]}, f)
        with self.assertRaisesRegex(ValueError, re.escape(tar) + r": sample s/tuple_000000 is "
                                    r"an N-view sample \(occgt tuples --shards"):
            ShardDataset(folder)

    def test_bad_folders(self) -> None:
        empty = common.scratch("sd_no_index")
        with self.assertRaisesRegex(ValueError, re.escape(os.path.join(empty, "index.json")) +
                                    r": missing \(expected the split's wids shard index"):
            ShardDataset(empty)
        with open(os.path.join(empty, "index.json"), "w") as f:
            f.write('{"shardlist": 3}')
        with self.assertRaisesRegex(ValueError, r"index.json: expected an object with a "
                                    r"\"shardlist\" array"):
            ShardDataset(empty)
        # An index of another kind (validate refused it, ShardDataset read it).
        with open(os.path.join(empty, "index.json"), "w") as f:
            f.write('{"__kind__": "foo", "shardlist": []}')
        with self.assertRaisesRegex(ValueError, r"index.json: __kind__: expected "
                                    r"\"wids-shard-index-v1\", got \"foo\""):
            ShardDataset(empty)
        # A url that leaves the folder (or names a subfolder) is refused before any file is
        # opened: an edited index cannot point the reader at other tars.
        outside = os.path.join(self.full, "sd-full-000000.tar")
        for url in ["../" + os.path.basename(self.full) + "/sd-full-000000.tar", outside,
                    "sub/x-000000.tar", "..", ""]:
            with open(os.path.join(empty, "index.json"), "w") as f:
                json.dump({"__kind__": "wids-shard-index-v1",
                           "shardlist": [{"url": url, "nsamples": 1,
                                          "filesize": os.path.getsize(outside)}]}, f)
            with self.subTest(url=url), self.assertRaisesRegex(
                    ValueError, r"index\.json: shardlist\[0\]\.url: " + re.escape(json.dumps(url)) +
                    r" is not a file name in the split's folder"):
                ShardDataset(empty)

        missing = copy_split(self.full, "sd_missing_shard")
        os.remove(os.path.join(missing, "sd-full-000001.tar"))
        with self.assertRaisesRegex(ValueError, re.escape(os.path.join(
                missing, "sd-full-000001.tar")) + r": shard missing \(index.json lists it\)"):
            ShardDataset(missing)

        short = copy_split(self.full, "sd_short_shard")
        tar = os.path.join(short, "sd-full-000000.tar")
        size = os.path.getsize(tar)
        os.truncate(tar, size - 1024)
        with self.assertRaisesRegex(ValueError, re.escape(tar) + rf": {size - 1024} bytes, "
                                    rf"shorter than index.json's filesize {size}"):
            ShardDataset(short)

        count = copy_split(self.full, "sd_count")
        with open(os.path.join(count, "index.json")) as f:
            index = json.load(f)
        index["shardlist"][0]["nsamples"] += 1
        with open(os.path.join(count, "index.json"), "w") as f:
            json.dump(index, f)
        with self.assertRaisesRegex(ValueError, r"sd-full-000000.tar: 4 samples, index.json "
                                    r"says 5"):
            ShardDataset(count)

        garbled = copy_split(self.full, "sd_garbled")
        with open(os.path.join(garbled, "sd-full-000000.tar"), "r+b") as f:
            f.seek(10)
            f.write(b"X")  # inside the first member name: the header checksum fails
        with self.assertRaisesRegex(ValueError, r"sd-full-000000.tar: tar header at byte 0: "
                                    r"checksum mismatch"):
            ShardDataset(garbled)

        # A sample json without K0 (shard rewritten with tarfile, index.json's size updated):
        # indexing works, reading that sample names the json member and the field.
        nok = copy_split(self.full, "sd_json")
        tar = os.path.join(nok, "sd-full-000000.tar")
        with tarfile.open(tar) as src:
            members = [(m, src.extractfile(m).read()) for m in src.getmembers()]
        with tarfile.open(tar, "w", format=tarfile.USTAR_FORMAT) as dst:
            for k, (m, data) in enumerate(members):
                if k == 0:
                    meta = json.loads(data)
                    del meta["K0"]
                    data = json.dumps(meta).encode()
                    m.size = len(data)
                dst.addfile(m, io.BytesIO(data))
        with open(os.path.join(nok, "index.json")) as f:
            index = json.load(f)
        index["shardlist"][0]["filesize"] = os.path.getsize(tar)
        with open(os.path.join(nok, "index.json"), "w") as f:
            json.dump(index, f)
        ds = ShardDataset(nok)
        self.assertTrue(torch.equal(ds[1]["K0"], self.expected(1)["K0"]))
        with self.assertRaisesRegex(ValueError, re.escape(f"{tar}: {ds.key(0)}.json: expected "
                                                          f"the sample fields") +
                                    r".*KeyError: 'K0'"):
            ds[0]

        # The dense split has no images and no depth: asking for them names the member.
        first = ShardDataset(self.dense, images=False, depth=False).key(0)
        with self.assertRaisesRegex(ValueError, r"sd-dense-000000.tar: sample " +
                                    re.escape(first) + r" has no image0.png or image0.jpg "
                                    r"member \(asked for by images=True / color=True\)"):
            ShardDataset(self.dense, images=True)
        with self.assertRaisesRegex(ValueError, r"has no depth0.npy member \(asked for by "
                                    r"depth=True\)"):
            ShardDataset(self.dense, depth=True)
        # Unset, the options are what the split stores: the defaults read a split of the
        # recipes' default sample.depth: false (they raised "has no depth0.npy member").
        stored = ShardDataset(self.dense)
        self.assertEqual((stored.occupancy, stored.images, stored.depth, stored.labels),
                         ("words", False, False, True))
        self.assertNotIn("depth0", stored[0])
        self.assertNotIn("image0", stored[0])
        self.assertIn("occ0", stored[0])
        full = ShardDataset(self.full)
        self.assertEqual((full.occupancy, full.images, full.depth, full.labels),
                         ("words", True, True, True))
        explicit = ShardDataset(self.full, occupancy="words", images=True, depth=True,
                                labels=True)
        self.assert_same(full[1], explicit[1], "defaults")


if __name__ == "__main__":
    unittest.main(verbosity=2)
