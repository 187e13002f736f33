"""One resolution of the pair options (libgt/truth/pair_settings.h): for every shipped recipe,
`occgt pair --recipe R`, `occgt occupancy --recipe R`, `occgt build R`, occgt.pair_from_scene
with the recipe's keys as keyword arguments, PairIndexDataset.from_split and
occgt.pair_options resolve equal options. The resolved options are compared (the
label_options, patch_options and occupancy_options a shard sample records), not only outputs.

Recipes whose dataset is here (demo, 7-Scenes and TartanAir samples) are built and every entry
point is checked on pairs of the build. The others (ScanNet, MegaDepth, the full TartanAir
test) have no data here: their settings are applied to the demo's generated scenes (--root,
--format generic), so the CLI, pair_from_scene and pair_options are compared on the same
stand-in scene.
"""
from __future__ import annotations

import glob
import gzip
import io
import json
import os
import subprocess
import sys
import tarfile
import unittest
from typing import Any, Dict, Iterator, List, Optional, Tuple

import numpy as np
import yaml

sys.path.insert(0, os.path.dirname(__file__))
import common  # noqa: E402

import occgt  # noqa: E402
from occgt.torch import PairIndexDataset  # noqa: E402

BUILT = {"demo": None, "sevenscenes-sample": "sevenscenes", "tartanair-sample": "tartanair"}


def run(*args: str, env: Optional[Dict[str, str]] = None) -> None:
    """The occgt binary (with an environment when given); AssertionError with its stderr."""
    r = subprocess.run([common.BINARY, *args], capture_output=True, text=True, env=env)
    if r.returncode != 0:
        raise AssertionError(f"occgt {' '.join(args)} failed ({r.returncode}):\n{r.stderr}")


def read_jsonl(path: str) -> List[Dict[str, Any]]:
    with open(path) as f:
        return [json.loads(line) for line in f if line.strip()]


def sample_jsons(split: str) -> Iterator[Dict[str, Any]]:
    """The .json member of every sample of a split (plain tarfile)."""
    for shard in common.read_json(os.path.join(split, "index.json"))["shardlist"]:
        with tarfile.open(os.path.join(split, shard["url"]), "r:") as tar:
            for member in tar:
                if member.name.endswith((".json", ".json.gz")):
                    data = tar.extractfile(member)
                    assert data is not None
                    raw = data.read()
                    yield json.loads(gzip.decompress(raw) if member.name.endswith(".gz") else raw)


def recipe_kwargs(recipe: Dict[str, Any]) -> Tuple[str, Dict[str, Any], str]:
    """(preset, pair_ground_truth keyword arguments, scope) of a recipe's keys, name for name."""
    labels = recipe.get("labels", {})
    kwargs: Dict[str, Any] = dict(labels.get("overrides", {}) or {})
    dataset = recipe.get("dataset", {})
    for k in ("min_depth_m", "max_depth_m"):
        if dataset.get(k) is not None:
            kwargs["dataset_" + k] = dataset[k]
    kwargs.update(recipe.get("patches", {}))
    occ = recipe.get("occupancy", {})
    sample = recipe.get("sample", {})
    kwargs["occupancy"] = bool(occ.get("enabled", True) and sample.get("occupancy", True))
    names = {"voxel_m": "voxel_m", "bins": "bins", "near_m": "near_m", "far_m": "far_m",
             "max_range_m": "max_range_m", "spacing": "spacing", "traversal": "traversal",
             "mode": "occupancy_mode", "downsample": "downsample",
             "remove_outliers": "remove_outliers", "outlier_k": "outlier_k",
             "outlier_stddev": "outlier_stddev"}
    kwargs.update({names[k]: v for k, v in occ.items() if k in names})
    scope = occ.get("scope", "pair")
    if scope == "window":
        scope = f"window:{occ.get('window', 2)}"
    elif scope == "scene":
        scope = f"scene:{occ.get('scene_stride', 10)}"
    return labels.get("preset", "default"), kwargs, scope


def occupancy_options_of(occupancy_json: Dict[str, Any]) -> Dict[str, Any]:
    """The options part of an `occgt occupancy` folder's occupancy.json."""
    bins = {k: v for k, v in occupancy_json["bins"].items() if k != "edges_m"}
    fusion = {k: v for k, v in occupancy_json["fusion"].items()
              if k in ("scope", "voxel_m", "max_range_m", "downsample", "remove_outliers")}
    if fusion["remove_outliers"]:  # a sample records the filter's parameters only when on
        fusion.update({k: occupancy_json["fusion"][k] for k in ("outlier_k", "outlier_stddev")})
    return {"mode": occupancy_json["mode"], "bins": bins, "fusion": fusion}


class ResolvedOptions(unittest.TestCase):
    demo_split = ""

    @classmethod
    def setUpClass(cls) -> None:
        cls.splits: Dict[str, str] = {}
        for name, shared in BUILT.items():
            if shared:
                common.shared(shared)
            out = common.scratch("pair_options_" + name)
            common.occgt("build", os.path.join(common.SOURCE, "recipes", name + ".yaml"), "--out",
                         out)
            cls.splits[name] = out
        cls.demo_split = cls.splits["demo"]

    def cli_options(self, recipe_path: str, occupancy: bool, scene: str, id0: str, id1: str,
                    extra: List[str], env: Optional[Dict[str, str]] = None) -> Dict[str, Any]:
        """The options `occgt pair --recipe` and `occgt occupancy --recipe` record."""
        out = common.scratch("pair_options_cli")
        run("pair", "--recipe", recipe_path, "--scene", scene, "--frames", f"{id0},{id1}",
            "--out", os.path.join(out, "pair"), *extra, env=env)
        meta = common.read_json(os.path.join(out, "pair", "meta.json"))
        got: Dict[str, Any] = {"label_options": meta["label_options"],
                               "patch_options": meta["patch_options"], "occupancy_options": None}
        if occupancy:
            run("occupancy", "--recipe", recipe_path, "--scene", scene, "--frames",
                f"{id0},{id1}", "--out", os.path.join(out, "occ"), *extra, env=env)
            occ = common.read_json(os.path.join(out, "occ", "occupancy.json"))
            got["occupancy_options"] = occupancy_options_of(occ)
            # occgt occupancy's validity range is the labels' (the same resolution).
            self.assertEqual(occ["fusion"]["min_depth_m"], meta["label_options"]["min_depth_m"])
            self.assertEqual(occ["fusion"]["max_depth_m"], meta["label_options"]["max_depth_m"])
        return got

    def python_options(self, recipe: Dict[str, Any], root: str, fmt: str, scene_name: str,
                       id0: str, id1: str) -> Dict[str, Any]:
        """pair_from_scene's resolved options, and pair_options' from the same arguments."""
        preset, kwargs, scope = recipe_kwargs(recipe)
        width, height = recipe.get("resolution", [occgt.PAIR_DEFAULTS["width"],
                                                  occgt.PAIR_DEFAULTS["height"]])
        scene = occgt.open_dataset(root, fmt).scene(scene_name)
        got = occgt.pair_from_scene(scene, id0, id1, width=width, height=height, preset=preset,
                                    scope=scope, **kwargs)["options"]
        again = occgt.pair_options(
            preset, dataset_depth_range=(scene.min_depth_m, scene.max_depth_m), **kwargs)
        self.assertEqual(got, again)
        return dict(got)

    def test_built_recipes(self) -> None:
        for name, split in self.splits.items():
            path = os.path.join(common.SOURCE, "recipes", name + ".yaml")
            with open(path) as f:
                recipe = yaml.safe_load(f)
            built = common.read_json(os.path.join(split, "recipe.json"))
            root = built["dataset"]["root"] or os.path.join(split, "data")
            fmt = "generic" if built["dataset"]["format"] == "synthetic" else built["dataset"]["format"]
            ds = PairIndexDataset.from_split(split)
            lines = read_jsonl(os.path.join(split, "pairs.jsonl"))
            self.assertGreater(len(lines), 0, name)
            samples = {m["key"]: m for m in sample_jsons(split)}
            for i in sorted({0, len(lines) // 2, len(lines) - 1}):
                line = lines[i]
                key = f"{line['scene']}/{line['frame0']['id']}_{line['frame1']['id']}"
                meta = samples[key]
                want = {k: meta[k] for k in ("label_options", "patch_options",
                                             "occupancy_options")}
                where = f"{name} {key}"
                self.assertEqual(ds.pair_options(i), want, where)
                id0, id1 = line["frame0"]["id"], line["frame1"]["id"]
                extra = ["--root", root] if built["dataset"]["format"] == "synthetic" else []
                self.assertEqual(self.cli_options(path, want["occupancy_options"] is not None,
                                                  line["scene"], id0, id1, extra), want, where)
                self.assertEqual(self.python_options(recipe, root, fmt, line["scene"], id0, id1),
                                 want, where)

    def test_recipes_without_their_data(self) -> None:
        """The other shipped recipes, on the demo's generated scene."""
        root = os.path.join(self.demo_split, "data")
        line = read_jsonl(os.path.join(self.demo_split, "pairs.jsonl"))[0]
        scene, id0, id1 = line["scene"], line["frame0"]["id"], line["frame1"]["id"]
        # Files a recipe names must exist to load it: point them at stand-ins.
        env = dict(os.environ)
        standin = os.path.join(common.scratch("pair_options_standin"), "list.txt")
        with open(standin, "w") as f:
            f.write("")
        env["MEGADEPTH_1500_LIST"] = standin
        others = sorted(set(glob.glob(os.path.join(common.SOURCE, "recipes", "*.yaml"))) -
                        {os.path.join(common.SOURCE, "recipes", n + ".yaml") for n in BUILT})
        self.assertGreaterEqual(len(others), 5, others)
        presets = set()
        for path in others:
            with open(path) as f:
                recipe = yaml.safe_load(f)
            preset, kwargs, _ = recipe_kwargs(recipe)
            presets.add(preset)
            # The demo's scene has no mesh: a recipe rendering depth reads the sensor's here.
            sensor = ["--depth-source", "sensor"] if recipe["dataset"].get("depth_source") else []
            cli = self.cli_options(path, kwargs["occupancy"], scene, id0, id1,
                                   ["--root", root, "--format", "generic", *sensor], env=env)
            py = self.python_options(recipe, root, "generic", scene, id0, id1)
            self.assertEqual(cli, py, path)
            self.assertEqual(cli["label_options"]["abs_tol_m"],
                             occgt.pair_options(preset)["label_options"]["abs_tol_m"]
                             if "abs_tol_m" not in kwargs else kwargs["abs_tol_m"], path)
        self.assertIn("megadepth", presets)  # a preset other than the default is exercised

    def test_point_filters(self) -> None:
        """occupancy.downsample / remove_outliers / outlier_k / outlier_stddev: a recipe's keys
        reach the build's samples, recipe.json, `occgt pair/occupancy --recipe`,
        pair_from_scene and PairIndexDataset.from_split alike; the parameters of a filter that
        is off, and the filters under two_point, are refused everywhere."""
        with open(os.path.join(common.SOURCE, "recipes", "demo.yaml")) as f:
            recipe = yaml.safe_load(f)
        recipe["dataset"]["synthetic"].update({"scenes": 1, "frames": 10})
        recipe["selection"]["quota_per_scene"] = 2
        for k in ("loftr_export", "gluefactory_export", "dust3r_export"):
            recipe.pop(k)
        recipe["occupancy"].update({"downsample": True, "remove_outliers": True,
                                    "outlier_k": 8, "outlier_stddev": 1.5})
        folder = common.scratch("pair_options_filters")
        path = os.path.join(folder, "filters.yaml")
        with open(path, "w") as f:
            yaml.safe_dump(recipe, f)
        split = os.path.join(folder, "out")
        common.occgt("build", path, "--out", split)
        occ = common.read_json(os.path.join(split, "recipe.json"))["occupancy"]
        self.assertEqual({k: occ[k] for k in ("downsample", "remove_outliers", "outlier_k",
                                              "outlier_stddev")},
                         {"downsample": True, "remove_outliers": True, "outlier_k": 8,
                          "outlier_stddev": 1.5})
        ds = PairIndexDataset.from_split(split)
        line = read_jsonl(os.path.join(split, "pairs.jsonl"))[0]
        id0, id1 = line["frame0"]["id"], line["frame1"]["id"]
        meta = {m["key"]: m for m in sample_jsons(split)}[f"{line['scene']}/{id0}_{id1}"]
        want = {k: meta[k] for k in ("label_options", "patch_options", "occupancy_options")}
        self.assertEqual(want["occupancy_options"]["fusion"],
                         {"scope": "pair", "voxel_m": 0.05, "max_range_m": 8.0,
                          "downsample": True, "remove_outliers": True, "outlier_k": 8,
                          "outlier_stddev": 1.5})
        self.assertGreater(meta["occupancy"]["fusion"]["stats"]["outliers_removed"], 0)
        root = os.path.join(split, "data")
        self.assertEqual(ds.pair_options(0), want)
        self.assertEqual(self.cli_options(path, True, line["scene"], id0, id1, ["--root", root]),
                         want)
        self.assertEqual(self.python_options(recipe, root, "generic", line["scene"], id0, id1),
                         want)
        # The item's volumes are the shard's (the filters applied on the fly too), and
        # differ from the unfiltered ones (else the comparison proves nothing).
        members: Dict[str, bytes] = {}
        for shard in common.read_json(os.path.join(split, "index.json"))["shardlist"]:
            with tarfile.open(os.path.join(split, shard["url"]), "r:") as tar:
                for m in tar:
                    data = tar.extractfile(m)
                    if data is not None:  # members may be gzipped (sample.compression)
                        raw = data.read()
                        members[m.name.removesuffix(".gz")] = (
                            gzip.decompress(raw) if m.name.endswith(".gz") else raw)
        key = f"{line['scene']}/{id0}_{id1}"
        unfiltered = PairIndexDataset.from_split(split, downsample=False, remove_outliers=False,
                                                 outlier_k=None, outlier_stddev=None)
        differ = 0
        for k in ("occ0", "known0", "occ1", "known1"):
            shard = np.load(io.BytesIO(members[f"{key}.{k}.npy"]))
            self.assertTrue(np.array_equal(ds[0][k].numpy().view(np.uint64), shard), k)
            differ += int((unfiltered[0][k].numpy().view(np.uint64) != shard).sum())
        self.assertGreater(differ, 0)
        # A filter's parameter without the filter, and a filter under two_point: refused.
        bad = dict(recipe, occupancy=dict(recipe["occupancy"], remove_outliers=False))
        with open(path, "w") as f:
            yaml.safe_dump(bad, f)
        r = subprocess.run([common.BINARY, "build", path, "--out", split, "--dry-run"],
                           capture_output=True, text=True)
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("occupancy.outlier_k: used with remove_outliers on only", r.stderr)
        with self.assertRaisesRegex(ValueError, "^outlier_stddev: used with remove_outliers"):
            occgt.pair_options(occupancy=True, outlier_stddev=1.0)
        with self.assertRaisesRegex(ValueError, "downsample filters the fused points for mode "
                                                "octomap only"):
            occgt.pair_options(occupancy=True, occupancy_mode="two_point", downsample=True)
        # A scope map fused without the filters is refused by a pair that asks for them.
        scene = occgt.open_dataset(root, "generic").scene(line["scene"])
        fused = scene.fuse(id0, id1, 320, 240, scope="window:1")
        depth0, K0, pose0 = scene.load(id0, 320, 240)
        depth1, K1, pose1 = scene.load(id1, 320, 240)
        with self.assertRaisesRegex(ValueError, "^scope_map: fused with downsample off, "
                                                "remove_outliers off; expected the same here"):
            occgt.pair_ground_truth(depth0, depth1, K0, K1, pose0, pose1, occupancy=True,
                                    remove_outliers=True, scope_map=fused)

    def test_defaults_come_from_the_cpp(self) -> None:
        """PAIR_DEFAULTS are the options of default settings, and pair_options() is them."""
        d = occgt.PAIR_DEFAULTS
        o = occgt.pair_options(occupancy=True)
        self.assertEqual(o["patch_options"], {"stride": d["stride"], "anchor": d["anchor"],
                                              "mutual": d["mutual"]})
        self.assertEqual(o["occupancy_options"]["bins"]["far_m"], d["far_m"])
        # The ray range is the last bin edge unless given apart.
        self.assertEqual(o["occupancy_options"]["fusion"]["max_range_m"], d["far_m"])
        far = occgt.pair_options(occupancy=True, far_m=2 * d["far_m"])["occupancy_options"]
        self.assertEqual(far["fusion"]["max_range_m"], 2 * d["far_m"])
        apart = occgt.pair_options(occupancy=True, max_range_m=3.0)["occupancy_options"]
        self.assertEqual(apart["fusion"]["max_range_m"], 3.0)
        self.assertEqual(o["label_options"]["max_depth_m"], d["max_depth_m"])
        # The order: the dataset's range, then a range set for the dataset, then overrides;
        # occ2net-compat ignores the dataset's range but not one asked for explicitly.
        r = occgt.pair_options(dataset_depth_range=(0.5, 9.0))["label_options"]
        self.assertEqual((r["min_depth_m"], r["max_depth_m"]), (0.5, 9.0))
        r = occgt.pair_options(dataset_depth_range=(0.5, 9.0), dataset_max_depth_m=7.0,
                               min_depth_m=0.25)["label_options"]
        self.assertEqual((r["min_depth_m"], r["max_depth_m"]), (0.25, 7.0))
        c = occgt.pair_options("occ2net-compat", dataset_depth_range=(0.5, 9.0))["label_options"]
        self.assertEqual(c["min_depth_m"], 0.0)
        c = occgt.pair_options("occ2net-compat", dataset_depth_range=(0.5, 9.0),
                               dataset_max_depth_m=7.0)["label_options"]
        self.assertEqual(c["max_depth_m"], 7.0)
        with self.assertRaisesRegex(TypeError, "unexpected keyword argument 'voxel'"):
            occgt.pair_options(voxel=0.1)
        with self.assertRaisesRegex(ValueError, "^options: labels: max_depth_m"):
            occgt.pair_options(min_depth_m=5.0, max_depth_m=1.0)

    def test_no_upper_depth_limit(self) -> None:
        """max_depth_m inf (no upper limit): the options record null, as meta.json and a
        sample's json do (JSON has no infinity), not inf; pair_ground_truth's dict equals the
        file of `occgt pair --max-depth-m inf`."""
        self.assertIsNone(occgt.pair_options(max_depth_m=float("inf"))["label_options"]
                          ["max_depth_m"])
        self.assertIsNone(occgt.pair_options(dataset_max_depth_m=float("inf"))["label_options"]
                          ["max_depth_m"])
        root = os.path.join(self.demo_split, "data")
        out = common.scratch("pair_options_inf")
        run("pair", "--root", root, "--format", "generic", "--scene", "synth_000", "--frames",
            "000000,000001", "--resolution", "64x48", "--max-depth-m", "inf", "--out", out)
        meta = common.read_json(os.path.join(out, "meta.json"))
        scene = occgt.open_dataset(root, "generic").scene("synth_000")
        got = occgt.pair_from_scene(scene, "000000", "000001", width=64, height=48,
                                    max_depth_m=float("inf"))["options"]
        self.assertEqual(got["label_options"], meta["label_options"])
        self.assertIsNone(meta["label_options"]["max_depth_m"])


if __name__ == "__main__":
    unittest.main()
