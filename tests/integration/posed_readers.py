"""Readers of occgt's glue-factory and DUSt3R exports (docs/EXPORTS.md), each written here
from the facts of that trainer's own loader, and the checks loftr_tree_test.py runs on the
same builds (the demo and both real samples) against occgt's shard metadata.

glue-factory, PosedImageDataset (gluefactory/datasets/posed_images.py, with
gluefactory/geometry/reconstruction.py for Pose and Camera):
- the scenes are the entries of the root (root.glob("*")) when no scene_list is given;
- conf.views "{scene}/views.txt": one line per view, split on single spaces: name, then
  R (9 numbers, row-major) and t (3) of the world-to-camera pose (Pose.from_Rt, kept as
  T_w2cam), then a COLMAP camera: model, width, height, params (PINHOLE: fx fy cx cy, in
  COLMAP's convention: the centre of the top-left pixel is (0.5, 0.5));
- the image is conf.image_dir "{scene}/images" / name; the depth is conf.depth_dir
  "{scene}/depths" / (name.split('.')[0] + "." + depth_format); with depth_format "png" it
  is cv2.imread(IMREAD_ANYDEPTH) / 256 (metres), valid where > 0, and must have the
  image's size (both are resized by one transform);
- conf.view_groups "{scene}/pairs.txt": lines (read_text().rstrip("\\n").split("\\n")) of
  image names split on " ", every token a view;
- T_0to1 = T_w2cam(view1) @ T_w2cam(view0).inv().

DUSt3R / MASt3R, the ScanNetpp dataset class (dust3r/datasets/scannetpp.py):
- np.load(ROOT/all_metadata.npz) (no allow_pickle) gives scenes, sceneids, images,
  intrinsics (astype float32), trajectories (astype float32) and pairs, of which it uses
  pairs[:, :2].astype(int) as the two global view indices;
- a view's folder is ROOT/scenes[sceneids[v]]; its image images/<images[v]>.jpg; its depth
  depth/<images[v]>.png read with IMREAD_UNCHANGED, / 1000 (metres), non-finite -> 0;
- for ScanNet++ the basenames images[v] are the DSLR image stems (DSC01234), the names its
  preprocessing (datasets_preprocess/preprocess_scannetpp.py) takes from `selection` of
  <scene>/selected_pairs.npz and writes as images/<stem>.jpg and scene_metadata.npz's images;
  occgt's export of a ScanNet++ build must name its views so (the frame ids), other datasets'
  views by frame number;
- camera_pose = trajectories[v] is camera-to-world; camera_intrinsics = intrinsics[v] is
  used with pixel centres at integer coordinates (depthmap_to_camera_coordinates in
  dust3r/utils/geometry.py meshes u = arange(W) against cu);
- its base class (dust3r/datasets/base/base_stereo_view_dataset.py) asserts a finite pose
  and depth map, and its crop around the principal point asserts that (cx, cy), rounded,
  lies more than W/5 and H/5 from every border; the image and depth map are cropped with
  one box, so they have one size.
"""
import json
import os
import sys

import cv2
import jsonschema
import numpy as np

import common


def fail(msg):
    sys.exit(f"FAIL: {msg}")


class GlueFactoryPosedReader:
    """glue-factory's PosedImageDataset over root with depth_format png, without torch."""

    def __init__(self, root):
        self.root = root
        self.scenes = sorted(os.listdir(root))
        self.views, self.items = {}, []
        for scene in self.scenes:
            views = {}
            with open(os.path.join(root, scene, "views.txt")) as f:
                for line in f:
                    tok = line.rstrip().split(" ")
                    name, rest = tok[0], tok[1:]
                    T = np.eye(4)
                    T[:3, :3] = np.array(rest[:9], dtype=np.float64).reshape(3, 3)
                    T[:3, 3] = np.array(rest[9:12], dtype=np.float64)
                    if rest[12] != "PINHOLE":
                        fail(f"{scene}/views.txt: camera model {rest[12]}")
                    camera = {"width": int(rest[13]), "height": int(rest[14]),
                              "params": np.array(rest[15:], dtype=np.float64)}
                    views[name] = (T, camera)
            for name in views:
                for path in (self.image_path(scene, name), self.depth_path(scene, name)):
                    if not os.path.exists(path):
                        fail(f"{path}: missing (glue-factory asserts it exists)")
            self.views[scene] = views
            text = open(os.path.join(root, scene, "pairs.txt")).read()
            self.items += [[scene] + p.split(" ") for p in text.rstrip("\n").split("\n")]

    def image_path(self, scene, name):
        return os.path.join(self.root, scene, "images", name)

    def depth_path(self, scene, name):
        return os.path.join(self.root, scene, "depths", f"{name.split('.')[0]}.png")

    def __getitem__(self, i):
        scene, *names = self.items[i]
        out = {"scene": scene, "names": names}
        for k, name in enumerate(names):
            T, camera = self.views[scene][name]
            img = cv2.imread(self.image_path(scene, name), cv2.IMREAD_COLOR)
            raw = cv2.imread(self.depth_path(scene, name), cv2.IMREAD_ANYDEPTH)
            if img is None or raw is None or raw.dtype != np.uint16:
                fail(f"{scene} {name}: image or uint16 depth png unreadable")
            if raw.shape != img.shape[:2] or (camera["width"], camera["height"]) != img.shape[1::-1]:
                fail(f"{scene} {name}: image {img.shape}, depth {raw.shape}, camera "
                     f"{camera['width']}x{camera['height']} differ")
            fx, fy, cx, cy = camera["params"]
            # COLMAP's corner convention -> pixel centres at integer coordinates.
            out[f"K{k}"] = np.array([[fx, 0, cx - 0.5], [0, fy, cy - 0.5], [0, 0, 1]])
            out[f"T_w2cam{k}"] = T
            out[f"image{k}"] = cv2.cvtColor(img, cv2.COLOR_BGR2RGB)
            out[f"raw{k}"] = raw
            out[f"depth{k}"] = raw.astype(np.float32) / 256
        out["T_0to1"] = out["T_w2cam1"] @ np.linalg.inv(out["T_w2cam0"])
        return out

    def __len__(self):
        return len(self.items)


class Dust3rScanNetppReader:
    """DUSt3R's ScanNetpp dataset over ROOT, before its crop/resize step."""

    def __init__(self, root):
        self.root = root
        with np.load(os.path.join(root, "all_metadata.npz")) as data:
            self.scenes = data["scenes"]
            self.sceneids = data["sceneids"]
            self.images = data["images"]
            self.intrinsics = data["intrinsics"].astype(np.float32)
            self.trajectories = data["trajectories"].astype(np.float32)
            self.pairs = data["pairs"][:, :2].astype(int)
            self.raw = {k: data[k] for k in data.files}

    def view(self, v):
        scene_dir = os.path.join(self.root, str(self.scenes[self.sceneids[v]]))
        basename = str(self.images[v])
        img = cv2.imread(os.path.join(scene_dir, "images", basename + ".jpg"), cv2.IMREAD_COLOR)
        raw = cv2.imread(os.path.join(scene_dir, "depth", basename + ".png"), cv2.IMREAD_UNCHANGED)
        if img is None or raw is None or raw.dtype != np.uint16 or raw.ndim != 2:
            fail(f"{scene_dir} {basename}: image or uint16 depth png unreadable")
        depth = raw.astype(np.float32) / 1000
        depth[~np.isfinite(depth)] = 0
        pose, K = self.trajectories[v], self.intrinsics[v]
        H, W = raw.shape
        cx, cy = K[:2, 2].round().astype(int)
        if img.shape[:2] != raw.shape or not np.isfinite(pose).all() or \
                min(cx, W - cx) <= W / 5 or min(cy, H - cy) <= H / 5:
            fail(f"{scene_dir} {basename}: DUSt3R's view checks fail (size {img.shape} vs "
                 f"{raw.shape}, pose {pose.tolist()}, principal point {cx}, {cy})")
        return {"img": cv2.cvtColor(img, cv2.COLOR_BGR2RGB), "raw": raw, "depthmap": depth,
                "camera_pose": self.trajectories[v], "camera_intrinsics": self.intrinsics[v],
                "scene": str(self.scenes[self.sceneids[v]]), "basename": basename}

    def __len__(self):
        return len(self.pairs)

    def __getitem__(self, i):
        return [self.view(v) for v in self.pairs[i]]


def shard_images(build, samples):
    """{(scene, number0, number1): (image0, image1)} as RGB arrays, from the shards."""
    import tarfile
    out, tars = {}, {}
    for key, (line, _meta, _d0, _d1) in samples.items():
        tf = tars.setdefault(line["shard"], tarfile.open(os.path.join(build, line["shard"])))
        names = tf.getnames()
        imgs = []
        for k in "01":
            member = next(n for n in names if n.startswith(line["key"] + f".image{k}."))
            buf = np.frombuffer(tf.extractfile(member).read(), np.uint8)
            imgs.append(cv2.cvtColor(cv2.imdecode(buf, cv2.IMREAD_COLOR), cv2.COLOR_BGR2RGB))
        out[key] = imgs
    return out


def check_depth(label, raw, ref, units):
    """raw: the export's uint16 at units per metre; ref: occgt's depth0/1.npy, same size."""
    if raw.shape != ref.shape:
        fail(f"{label}: depth {raw.shape}, occgt's {ref.shape}")
    top = 65535 / units
    ok = np.isfinite(ref) & (ref > 0) & (ref <= top)
    err = np.abs(raw.astype(np.float64) / units - ref.astype(np.float64))[ok]
    if ok.sum() < 0.3 * ok.size or err.max() > 0.5 / units + 1e-6:
        fail(f"{label}: depth off by {err.max():.6f} m (want <= half a unit, {0.5 / units} m)")
    if np.any(raw[~ok] != 0):
        fail(f"{label}: depth where occgt has none (or beyond {top:.3f} m)")


def check_image(label, got, shard_image):
    """The export's JPEG and the shard's image are the same colour resize of one frame."""
    if got.shape != shard_image.shape:
        fail(f"{label}: image {got.shape}, shard's {shard_image.shape}")
    diff = np.abs(got.astype(np.int16) - shard_image.astype(np.int16)).mean()
    if diff > 4.0:
        fail(f"{label}: image differs from the shard's by {diff:.2f} levels on average")


def validate_export_json(path, fmt, want_scenes, views, pairs):
    doc = json.load(open(path))
    schema = json.load(open(os.path.join(common.SOURCE, "schemas", "posed_export.schema.json")))
    jsonschema.validate(doc, schema)
    if doc["format"] != fmt or doc["views"] != views or doc["pairs"] != pairs:
        fail(f"{path}: {doc}")
    if set(doc["scenes"].values()) != want_scenes:
        fail(f"{path}: scenes {doc['scenes']}, pairs.jsonl has {sorted(want_scenes)}")
    return doc


def check_gluefactory(label, build, samples, images):
    root = os.path.join(build, "gluefactory", "data")
    doc_path = os.path.join(build, "gluefactory", "export.json")
    scene_of = json.load(open(doc_path))["scenes"]
    reader = GlueFactoryPosedReader(root)
    seen, used = set(), {}
    for i in range(len(reader)):
        item = reader[i]
        if len(item["names"]) != 2:
            fail(f"{label}: pairs.txt line {item['names']} is not two views")
        scene = scene_of[item["scene"]]
        n0, n1 = (int(n.split(".")[0]) for n in item["names"])
        key = (scene, n0, n1)
        if key not in samples:
            fail(f"{label}: glue-factory pair {key} is not in pairs.jsonl")
        seen.add(key)
        line, meta, d0, d1 = samples[key]
        what = f"{label} gluefactory {key}"
        for k in "01":
            if not np.allclose(item[f"K{k}"], np.array(meta[f"K{k}"]), rtol=0, atol=1e-9):
                fail(f"{what}: K{k} {item[f'K{k}'].tolist()} vs occgt's {meta[f'K{k}']}")
        if not np.allclose(item["T_0to1"], np.array(meta["T_0to1"]), rtol=0, atol=1e-9):
            fail(f"{what}: T_0to1 {item['T_0to1'].tolist()} vs occgt's {meta['T_0to1']}")
        for k, d in (("0", d0), ("1", d1)):
            check_depth(f"{what} depth{k}", item[f"raw{k}"], d, 256)
            check_image(f"{what} image{k}", item[f"image{k}"], images[key][int(k)])
        used.setdefault(item["scene"], set()).update((n0, n1))
    if seen != set(samples):
        fail(f"{label}: glue-factory reads {len(seen)} pairs, pairs.jsonl has {len(samples)}")
    # pair_scores.txt: the pairs.txt lines with the score and both overlaps.
    for folder in reader.scenes:
        pairs = open(os.path.join(root, folder, "pairs.txt")).read().split("\n")[:-1]
        rows = [l.split(" ") for l in open(os.path.join(root, folder, "pair_scores.txt"))]
        if [" ".join(r[:2]) for r in rows] != pairs:
            fail(f"{label} {folder}: pair_scores.txt lines are not pairs.txt's")
        for r in rows:
            key = (scene_of[folder], int(r[0].split(".")[0]), int(r[1].split(".")[0]))
            m = samples[key][0]["score_metrics"]
            want = [np.mean([m["01"]["overlap"], m["10"]["overlap"]]), m["01"]["overlap"],
                    m["10"]["overlap"]]
            if not np.allclose([float(x) for x in r[2:5]], want, rtol=0, atol=1e-6):
                fail(f"{label} {folder}: scores {r[2:5]} vs occgt's {want}")
        # Exactly the views the pairs use.
        got = sorted(os.listdir(os.path.join(root, folder, "images")))
        if got != sorted(f"{n}.jpg" for n in used[folder]) or len(reader.views[folder]) != len(got):
            fail(f"{label} {folder}: images {got[:4]}..., used {sorted(used[folder])[:4]}...")
    validate_export_json(doc_path, "gluefactory", {k[0] for k in samples},
                         sum(len(v) for v in used.values()), len(samples))


def check_dust3r(label, build, samples, images):
    root = os.path.join(build, "dust3r")
    reader = Dust3rScanNetppReader(root)
    scene_of = json.load(open(os.path.join(root, "export.json")))["scenes"]
    raw = reader.raw
    for k in ("scenes", "images"):
        if raw[k].dtype.kind != "U":
            fail(f"{label}: all_metadata.npz {k} has dtype {raw[k].dtype}, want numpy str")
    if raw["pairs"].shape != (len(samples), 5) or raw["intrinsics"].shape[1:] != (3, 3):
        fail(f"{label}: all_metadata.npz pairs {raw['pairs'].shape}")
    with open(os.path.join(build, "recipe.json")) as f:
        by_stem = json.load(f)["dataset"]["format"] == "scannetpp"
    # (scene, frame id) -> frame number, from occgt's own pair lines.
    number_of = {}
    for key, (line, *_rest) in samples.items():
        for k in ("frame0", "frame1"):
            number_of[(key[0], line[k]["id"])] = int(line[k]["number"])

    def number(scene, basename):
        if by_stem:  # ScanNet++: DUSt3R's basename is the image stem = occgt's frame id
            if (scene, basename) not in number_of:
                fail(f"{label}: dust3r view {scene}/{basename} is not a frame id of a pair "
                     "(ScanNet++ views are named by their image stem)")
            return number_of[(scene, basename)]
        if not basename.isdigit():
            fail(f"{label}: dust3r view {scene}/{basename}: expected the frame number")
        return int(basename)

    seen = set()
    for i in range(len(reader)):
        v0, v1 = reader[i]
        if v0["scene"] != v1["scene"]:
            fail(f"{label}: dust3r pair {i} joins two scenes")
        scene = scene_of[v0["scene"]]
        key = (scene, number(scene, v0["basename"]), number(scene, v1["basename"]))
        if key not in samples:
            fail(f"{label}: dust3r pair {key} is not in pairs.jsonl")
        seen.add(key)
        line, meta, d0, d1 = samples[key]
        what = f"{label} dust3r {key}"
        for k, v in (("0", v0), ("1", v1)):
            if not np.allclose(v["camera_intrinsics"], np.array(meta[f"K{k}"]), rtol=1e-6, atol=1e-4):
                fail(f"{what}: K{k} {v['camera_intrinsics'].tolist()} vs occgt's {meta[f'K{k}']}")
            check_depth(f"{what} depth{k}", v["raw"], d0 if k == "0" else d1, 1000)
            check_image(f"{what} image{k}", v["img"], images[key][int(k)])
        # The loader's float32 poses, and the float64 arrays they come from.
        T32 = np.linalg.inv(v1["camera_pose"].astype(np.float64)) @ v0["camera_pose"]
        if not np.allclose(T32, np.array(meta["T_0to1"]), rtol=0, atol=1e-4):
            fail(f"{what}: float32 T_0to1 {T32.tolist()} vs occgt's {meta['T_0to1']}")
        p0, p1 = reader.pairs[i]
        T64 = np.linalg.inv(raw["trajectories"][p1]) @ raw["trajectories"][p0]
        if not np.allclose(T64, np.array(line["T_0to1"]), rtol=0, atol=1e-9):
            fail(f"{what}: T_0to1 {T64.tolist()} vs occgt's {line['T_0to1']}")
        m = line["score_metrics"]
        want = [np.mean([m["01"]["overlap"], m["10"]["overlap"]]), m["01"]["overlap"],
                m["10"]["overlap"]]
        if not np.allclose(raw["pairs"][i, 2:], want, rtol=0, atol=1e-12):
            fail(f"{what}: pairs scores {raw['pairs'][i, 2:].tolist()} vs occgt's {want}")
    if seen != set(samples):
        fail(f"{label}: dust3r reads {len(seen)} pairs, pairs.jsonl has {len(samples)}")
    # scene_metadata.npz: the same views and pairs with scene-local indices.
    for s, folder in enumerate(reader.scenes):
        with np.load(os.path.join(root, str(folder), "scene_metadata.npz")) as sm:
            first = int(raw["counts"][s])
            mine = np.flatnonzero(raw["sceneids"] == s)
            if not (np.array_equal(mine, np.arange(first, first + len(mine))) and
                    np.array_equal(sm["images"], raw["images"][mine]) and
                    np.array_equal(sm["trajectories"], raw["trajectories"][mine]) and
                    np.array_equal(sm["intrinsics"], raw["intrinsics"][mine])):
                fail(f"{label} {folder}: scene_metadata.npz views differ from all_metadata.npz")
            glob_pairs = raw["pairs"][np.isin(raw["pairs"][:, 0], mine)].copy()
            glob_pairs[:, :2] -= first
            if not np.array_equal(sm["pairs"], glob_pairs):
                fail(f"{label} {folder}: scene_metadata.npz pairs differ from all_metadata.npz")
        if sorted(os.listdir(os.path.join(root, str(folder), "images"))) != sorted(
                f"{b}.jpg" for b in raw["images"][mine]):
            fail(f"{label} {folder}: images/ holds other files than the views")
        if by_stem:
            # DUSt3R's preprocessing names images/<stem>.jpg after selected_pairs' selection.
            with np.load(os.path.join(root, str(folder), "selected_pairs.npz")) as sp:
                if [str(x) for x in sp["selection"]] != [str(x) for x in raw["images"][mine]]:
                    fail(f"{label} {folder}: selected_pairs.npz selection "
                         f"{sp['selection'][:3]}... differs from the view names "
                         f"{raw['images'][mine][:3]}...")
    validate_export_json(os.path.join(root, "export.json"), "dust3r", {k[0] for k in samples},
                         len(raw["images"]), len(samples))


def check_build(label, build, samples):
    """Both readers on one build; `samples` as loftr_tree_test.occgt_samples gives it."""
    images = shard_images(build, samples)
    check_gluefactory(label, build, samples, images)
    check_dust3r(label, build, samples, images)
