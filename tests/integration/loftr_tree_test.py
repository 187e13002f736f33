"""The LoFTR export tree (DIR/loftr/data, ScanNet's exported layout; docs/EXPORTS.md) read
the way LoFTR's unchanged ScanNetDataset reads a dataset, for the demo and the two real
samples, against occgt's own sample metadata (shard json, depth0/1.npy) and pairs.jsonl.

The reader below follows the facts of LoFTR's loader (src/datasets/scannet.py and
src/utils/dataset.py), written here from those facts:
- the list file names npz files under NPZ_ROOT; each holds `name` rows (scene, sub-scene,
  frame0, frame1) and, for training, `score` (kept where score > min_overlap_score);
- the scene folder is f"scene{scene:04d}_{sub:02d}" under DATA_ROOT;
- colour from <folder>/color/{frame}.jpg (cv2.imread grey, resized to 640x480);
- depth from <folder>/depth/{frame}.png, cv2.imread(IMREAD_UNCHANGED) / 1000, not resized;
- pose: np.loadtxt(<folder>/pose/{frame}.txt, delimiter=' ') is camera-to-world; the
  loader inverts it (world-to-camera) and T_0to1 = pose1 @ inv(pose0);
- K = intrinsics.npz[folder], used with the 640x480 images and the depth as stored.
"""
import gzip
import io
import json
import os
import sys
import tarfile

import cv2
import jsonschema
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common  # noqa: E402
import posed_readers  # noqa: E402


def fail(msg):
    sys.exit(f"FAIL: {msg}")


class LoftrScanNetReader:
    """LoFTR's ScanNetDataset, one npz at a time, without torch."""

    def __init__(self, data_root, npz_path, intrinsic_path, min_overlap_score=0.0):
        self.root = data_root
        with np.load(npz_path) as data:
            names = data["name"]
            if "score" in data.files:
                self.scores = data["score"]
                names = names[self.scores > min_overlap_score]
            else:
                self.scores = None
            self.names = names
        self.intrinsics = dict(np.load(intrinsic_path))
        self._files = {}  # path -> what cv2 / np.loadtxt gave (the test reads frames once)

    def _read(self, path, how):
        if path not in self._files:
            self._files[path] = how(path)
        return self._files[path]

    def pose_w2c(self, folder, frame):
        c2w = self._read(os.path.join(self.root, folder, "pose", f"{frame}.txt"),
                         lambda p: np.loadtxt(p, delimiter=" "))
        return np.linalg.inv(c2w)

    def __getitem__(self, i):
        scene, sub, f0, f1 = (int(v) for v in self.names[i])
        folder = f"scene{scene:04d}_{sub:02d}"
        out = {"folder": folder, "frames": (f0, f1)}
        for k, f in (("0", f0), ("1", f1)):
            img = self._read(os.path.join(self.root, folder, "color", f"{f}.jpg"),
                             lambda p: cv2.imread(p, cv2.IMREAD_GRAYSCALE))
            if img is None:
                fail(f"{folder}/color/{f}.jpg: cv2 cannot read it")
            out["image" + k] = cv2.resize(img, (640, 480))
            raw = self._read(os.path.join(self.root, folder, "depth", f"{f}.png"),
                             lambda p: cv2.imread(p, cv2.IMREAD_UNCHANGED))
            if raw is None or raw.dtype != np.uint16 or raw.ndim != 2:
                fail(f"{folder}/depth/{f}.png: not a uint16 grey PNG")
            out["raw" + k] = raw
            out["depth" + k] = raw / 1000
        out["T_0to1"] = self.pose_w2c(folder, f1) @ np.linalg.inv(self.pose_w2c(folder, f0))
        out["K"] = self.intrinsics[folder].reshape(3, 3)
        return out


def to_640x480(k, width, height):
    k = np.asarray(k, dtype=np.float64)
    sx, sy = 640 / width, 480 / height
    return np.array([[sx * k[0][0], 0, sx * (k[0][2] + 0.5) - 0.5],
                     [0, sy * k[1][1], sy * (k[1][2] + 0.5) - 0.5], [0, 0, 1]])


def occgt_samples(build):
    """{(scene, number0, number1): (pairs.jsonl line, sample json, depth0, depth1)}."""
    out = {}
    with open(os.path.join(build, "pairs.jsonl")) as f:
        lines = [json.loads(l) for l in f if l.strip()]
    tars = {}
    for line in lines:
        tf = tars.setdefault(line["shard"], tarfile.open(os.path.join(build, line["shard"])))
        meta = json.load(tf.extractfile(line["key"] + ".json"))
        d = [np.load(io.BytesIO(gzip.decompress(tf.extractfile(line["key"] + f".depth{k}.npy.gz")
                                                .read()))) for k in "01"]  # deflate: the default
        out[(line["scene"], line["frame0"]["number"], line["frame1"]["number"])] = (line, meta, d[0], d[1])
    return out


def check_depth(label, raw, working, width, height):
    """raw: the export's uint16 mm at 640x480; working: occgt's float32 m at width x height."""
    if raw.shape != (480, 640):
        fail(f"{label}: depth png {raw.shape}, want (480, 640) (the size of intrinsics.npz's K)")
    # Nearest-neighbour under the pixel-centre rule: export pixel u takes floor((u + .5) / s).
    us = np.minimum(((np.arange(640) + 0.5) * width / 640).astype(int), width - 1)
    vs = np.minimum(((np.arange(480) + 0.5) * height / 480).astype(int), height - 1)
    ref = working if working.shape == (480, 640) else working[np.ix_(vs, us)]
    ok = np.isfinite(ref) & (ref > 0) & (ref <= 65.535)
    err = np.abs(raw.astype(np.float32) - ref * np.float32(1000))[ok]  # mm
    if ok.sum() < 0.3 * ok.size or err.max() > 0.5 + 1e-3:
        fail(f"{label}: depth off by {err.max():.3f} mm (want <= 0.5 mm) on {ok.sum()} px")
    # Invalid stays invalid: where occgt has no depth the export has 0 (no 65535 marker).
    if np.any(raw[~ok & ~(ref > 65.535)] != 0):
        fail(f"{label}: export has depth where occgt has none")
    if np.any(raw == 65535):
        fail(f"{label}: 65535 left in the depth png")


def check_build(label, build, kind):
    loftr = os.path.join(build, "loftr")
    data_root = os.path.join(loftr, "data")
    samples = occgt_samples(build)
    if kind == "test":
        npz_root, list_file = loftr, os.path.join(loftr, "test_list.txt")
    else:
        split = json.load(open(os.path.join(build, "recipe.json")))["split"]
        npz_root = os.path.join(loftr, "scene_data", split)
        list_file = os.path.join(loftr, f"{split}_list.txt")
    npz_names = [l.split()[0] for l in open(list_file) if l.strip()]
    scenes_txt = os.path.join(loftr, "scenes.txt")
    scene_names = open(scenes_txt).read().split("\n")[:-1] if os.path.exists(scenes_txt) else []
    seen = set()
    used_frames = {}
    depth_checked = set()
    for npz in npz_names:
        reader = LoftrScanNetReader(data_root, os.path.join(npz_root, npz),
                                    os.path.join(loftr, "intrinsics.npz"))
        for i in range(len(reader.names)):
            item = reader[i]
            scene_no = int(reader.names[i][0])
            scene = scene_names[scene_no] if scene_names else item["folder"]
            key = (scene, *item["frames"])
            if key not in samples:
                fail(f"{label}: {item['folder']} {item['frames']} is not a pair of pairs.jsonl")
            seen.add(key)
            line, meta, d0, d1 = samples[key]
            w, h = meta["resolution"]
            what = f"{label} {item['folder']} {item['frames']}"
            if not np.allclose(item["K"], to_640x480(meta["K0"], w, h), rtol=0, atol=1e-9):
                fail(f"{what}: K {item['K'].tolist()} vs occgt's K0 {meta['K0']} at {w}x{h}")
            for t in (np.array(line["T_0to1"]), np.array(meta["T_0to1"])):
                if not np.allclose(item["T_0to1"], t, rtol=0, atol=1e-9):
                    fail(f"{what}: T_0to1 {item['T_0to1'].tolist()} vs occgt's {t.tolist()}")
            if reader.scores is not None:
                agg = np.mean([line["score_metrics"][d]["overlap"] for d in ("01", "10")])
                if abs(float(reader.scores[i]) - agg) > 1e-6:
                    fail(f"{what}: score {reader.scores[i]} vs mean score_metrics overlap {agg}")
            for k, frame, d in (("0", item["frames"][0], d0), ("1", item["frames"][1], d1)):
                if (item["folder"], frame) not in depth_checked:  # a frame's depth, once
                    check_depth(f"{what} depth{k}", item["raw" + k], d, w, h)
                    depth_checked.add((item["folder"], frame))
            used_frames.setdefault(item["folder"], set()).update(item["frames"])
    if seen != set(samples):
        fail(f"{label}: {len(seen)} pairs read through LoFTR's loader, pairs.jsonl has "
             f"{len(samples)}")
    # Exactly the frames the index uses, and the intrinsic/ files ScanNet has.
    if sorted(os.listdir(data_root)) != sorted(used_frames):
        fail(f"{label}: scene folders {sorted(os.listdir(data_root))}, used {sorted(used_frames)}")
    intr = np.load(os.path.join(loftr, "intrinsics.npz"))
    for folder, frames in used_frames.items():
        for sub, ext in (("color", "jpg"), ("depth", "png"), ("pose", "txt")):
            got = sorted(os.listdir(os.path.join(data_root, folder, sub)))
            want = sorted(f"{n}.{ext}" for n in frames)
            if got != want:
                fail(f"{label} {folder}/{sub}: {got[:5]}..., want exactly {want[:5]}...")
        for n in frames:
            text = open(os.path.join(data_root, folder, "pose", f"{n}.txt"), "rb").read()
            if b"\r" in text or b"\t" in text or text.count(b"\n") != 4:
                fail(f"{label} {folder}/pose/{n}.txt: not 4 LF lines of space-separated numbers")
        k_depth = np.loadtxt(os.path.join(data_root, folder, "intrinsic", "intrinsic_depth.txt"),
                             delimiter=" ")
        if k_depth.shape != (4, 4) or not np.array_equal(k_depth[:3, :3], intr[folder]):
            fail(f"{label} {folder}: intrinsic_depth.txt {k_depth.tolist()} != intrinsics.npz")
        k_color = np.loadtxt(os.path.join(data_root, folder, "intrinsic", "intrinsic_color.txt"),
                             delimiter=" ")
        jpg = cv2.imread(os.path.join(data_root, folder, "color", f"{min(frames)}.jpg"))
        hc, wc = jpg.shape[:2]
        if not np.allclose(to_640x480(k_color[:3, :3], wc, hc), intr[folder], atol=1e-9):
            fail(f"{label} {folder}: intrinsic_color.txt at {wc}x{hc} is not intrinsics.npz's K")
    stats = json.load(open(os.path.join(loftr, "tree.json")))
    schema = json.load(open(os.path.join(common.SOURCE, "schemas", "loftr_tree.schema.json")))
    jsonschema.validate(stats, schema)
    if stats["frames"] != sum(len(f) for f in used_frames.values()):
        fail(f"{label}: tree.json {stats}")
    return stats


def build(recipe_name, out, env):
    common.occgt("build", "--json", os.path.join(common.SOURCE, "recipes", recipe_name), "--out",
                 out, env=env)


def main():
    common.shared("sevenscenes")
    common.shared("tartanair/hospital_sample")
    env = dict(os.environ, OCCGT_SHARED_DATA=common.SHARED)
    tmp = common.scratch("loftr_tree")
    runs = [("demo.yaml", "test"), ("sevenscenes-sample.yaml", "train"),
            ("tartanair-sample.yaml", "train")]
    for recipe, kind in runs:
        out = os.path.join(tmp, recipe.split(".")[0])
        build(recipe, out, env)
        stats = check_build(recipe, out, kind)
        print(f"{recipe}: {stats}")
        # The same build's glue-factory and DUSt3R exports (tests/integration/posed_readers.py).
        posed_readers.check_build(recipe, out, occgt_samples(out))
    # loftr_export.score: covisible (LoFTR's covisibility definition). The export keys are
    # part of the options digest: re-running the 7-Scenes build's folder with that recipe is
    # refused (it would find every shard complete and write no export), so it builds anew.
    text = open(os.path.join(common.SOURCE, "recipes", "sevenscenes-sample.yaml")).read()
    assert "loftr_export: {kind: train, tree: true}\n" in text
    covisible = os.path.join(tmp, "sevenscenes-covisible.yaml")
    text = text.replace("loftr_export: {kind: train, tree: true}",
                        "loftr_export: {kind: train, tree: true, score: covisible}")
    if common.SANITIZER:  # its own build: at half size under a sanitizer (the same checks)
        assert "resolution: [640, 480]\n" in text
        text = text.replace("resolution: [640, 480]", "resolution: [320, 240]")
    with open(covisible, "w") as f:
        f.write(text)
    r = common.occgt("build", covisible, "--out", os.path.join(tmp, "sevenscenes-sample"),
                     env=env, check=False)
    if r.returncode != 2 or "holds outputs of another recipe" not in r.stderr:
        fail(f"a re-run with another export score: exit {r.returncode}, {r.stderr!r}")
    out = os.path.join(tmp, "sevenscenes-covisible")
    common.occgt("build", "--json", covisible, "--out", out, env=env)
    samples = occgt_samples(out)
    split = json.load(open(os.path.join(out, "recipe.json")))["split"]
    n = 0
    for npz in open(os.path.join(out, "loftr", f"{split}_list.txt")).read().split():
        with np.load(os.path.join(out, "loftr", "scene_data", split, npz)) as data:
            names = open(os.path.join(out, "loftr", "scenes.txt")).read().split("\n")
            for name, score in zip(data["name"], data["score"]):
                m = samples[(names[name[0]], int(name[2]), int(name[3]))][0]["score_metrics"]
                want = np.mean([m[d]["consistent_overlap"] for d in ("01", "10")])
                if abs(float(score) - want) > 1e-6 or abs(want - np.mean(
                        [m[d]["overlap"] for d in ("01", "10")])) < 1e-3:
                    fail(f"covisible score {score} vs mean consistent_overlap {want}")
                n += 1
    if n != len(samples):
        fail(f"covisible: {n} scores, pairs.jsonl has {len(samples)}")
    print("loftr tree, gluefactory, dust3r: ok")


if __name__ == "__main__":
    main()
