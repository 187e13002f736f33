"""ScanNet++ end to end on occgt's own fixture (occgt synth --layout scannetpp): the files are
ScanNet++'s (COLMAP text models with an OPENCV_FISHEYE / OPENCV camera and COLMAP's +0.5
principal point, a binary PLY mesh, uint16 depth PNGs, an LZ4-record depth.bin); `occgt scan
--format scannetpp --json` validates against schemas/scan.schema.json and explains every
unusable image for both devices; a recipe with dataset.device iphone builds shards whose
images are the undistorted frames and whose depth has no value on anonymised pixels, and its
DUSt3R ScanNet++ export reads back through a reader written from DUSt3R's dataset class. The
DSLR (no depth files) builds with depth_source mesh, and its DUSt3R export holds that rendered
depth: checked against a brute-force ray cast of the fixture's own boxes (exact planar
geometry), anonymised pixels 0, plus selected_pairs.npz and scene_list.json."""
import gzip
import io
import json
import os
import re
import shutil
import struct
import sys
import tarfile

import cv2
import jsonschema
import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
import common  # noqa: E402
import posed_readers  # noqa: E402

FRAMES = 5


def check_fixture_files(scene):
    with open(os.path.join(scene, "dslr", "colmap", "cameras.txt")) as f:
        cams = [line.split() for line in f if line.strip() and not line.startswith("#")]
    assert len(cams) == 1 and cams[0][1] == "OPENCV_FISHEYE" and len(cams[0]) == 12, cams
    w, h = int(cams[0][2]), int(cams[0][3])
    cx = float(cams[0][6])
    assert (w, h) == (160, 120)
    # COLMAP convention: the principal point near the centre w/2 (first pixel centre 0.5).
    assert abs(cx - w / 2) < 2, cx
    with open(os.path.join(scene, "iphone", "colmap", "cameras.txt")) as f:
        cams = [line.split() for line in f if line.strip() and not line.startswith("#")]
    assert cams[0][1] == "OPENCV", cams
    with open(os.path.join(scene, "scans", "mesh_aligned_0.05.ply"), "rb") as f:
        head = f.read(400).split(b"end_header\n")[0].decode()
    assert "format binary_little_endian 1.0" in head and "property list uchar int" in head, head
    with open(os.path.join(scene, "dslr", "train_test_lists.json")) as f:
        lists = json.load(f)
    assert "DSC90001.JPG" in lists["test"], lists
    # depth.bin: records [uint32 LE size][LZ4 payload], one per iPhone frame (FRAMES + 1).
    with open(os.path.join(scene, "iphone", "depth.bin"), "rb") as f:
        data = f.read()
    at, records = 0, 0
    while at < len(data):
        (n,) = struct.unpack_from("<I", data, at)
        at += 4 + n
        records += 1
    assert at == len(data) and records == FRAMES + 1, (at, len(data), records)


def scan(root, device, validator):
    r = common.occgt("scan", root, "--format", "scannetpp", "--device", device, "--json")
    doc = json.loads(r.stdout)
    validator.validate(doc)
    assert doc["format"] == "scannetpp" and doc["device"] == device, doc
    return doc


def read_shard(path):
    """{key: {field: bytes}}, .npy.gz members inflated."""
    samples = {}
    with tarfile.open(path) as tar:
        for m in tar.getmembers():
            folder, base = os.path.split(m.name)
            stem, field = base.split(".", 1)
            data = tar.extractfile(m).read()
            if field.endswith(".gz"):
                field, data = field[:-3], gzip.decompress(data)
            samples.setdefault(f"{folder}/{stem}", {})[field] = data
    return samples


def occgt_samples(build):
    """{(scene, number0, number1): (pairs.jsonl line, sample json, depth0, depth1)}."""
    out = {}
    with open(os.path.join(build, "pairs.jsonl")) as f:
        lines = [json.loads(line) for line in f if line.strip()]
    for line in lines:
        with tarfile.open(os.path.join(build, line["shard"])) as tf:
            meta = json.load(tf.extractfile(line["key"] + ".json"))
            d = [np.load(io.BytesIO(gzip.decompress(
                tf.extractfile(line["key"] + f".depth{k}.npy.gz").read()))) for k in "01"]
        out[(line["scene"], line["frame0"]["number"], line["frame1"]["number"])] = (
            line, meta, d[0], d[1])
    return out


def main():
    with open(os.path.join(common.SOURCE, "schemas", "scan.schema.json")) as f:
        validator = jsonschema.Draft202012Validator(json.load(f))
    root = common.scratch("scannetpp")
    r = common.occgt("synth", "--out", root, "--layout", "scannetpp", "--scenes", 1, "--frames", FRAMES,
                     "--resolution", "160x120", "--seed", 1)
    assert "ScanNet++'s layout" in r.stdout, r.stdout
    scene = os.path.join(root, "data", "synthpp_000")
    check_fixture_files(scene)

    dslr = scan(root, "dslr", validator)
    s = dslr["scenes"][0]
    assert s["frames"] == FRAMES + 2, s
    assert s["unusable_reasons"] == {"colour: missing file": 1,
                                     "mask: covers the whole image": 1,
                                     "pose: image not in the COLMAP model": 1}, s
    assert s["usable"] == FRAMES - 1, s
    # The mesh comparison covers the frames the scan counts usable: not the one whose mask
    # covers the whole image (it was compared, all "neither").
    unusable = {e["frame"] for v in s["unusable_examples"].values() for e in v}
    compared = {f["id"] for f in s["mesh_depth"]["frames"]}
    assert len(compared) == s["usable"] and not compared & unusable, (compared, unusable)
    assert s["mesh_depth"]["unreadable"] == [], s["mesh_depth"]["unreadable"]
    # The undistorted pinhole camera: principal point (w/2, h/2) in OpenCV's convention.
    assert s["K"][0][2] == 80.0 and s["K"][1][2] == 60.0, s["K"]
    iphone = scan(root, "iphone", validator)
    s = iphone["scenes"][0]
    assert s["unusable_reasons"] == {"pose: image not in the COLMAP model": 1}, s
    assert s["depth_size"] == [256, 192], s

    assert not any(w.startswith("no mesh") for w in s["warnings"]), s["warnings"]
    # A scene without its mesh: scan says so (a DSLR build would drop every frame).
    nomesh = common.scratch("scannetpp_nomesh")
    shutil.copytree(os.path.join(root, "data"), os.path.join(nomesh, "data"))
    os.unlink(os.path.join(nomesh, "data", "synthpp_000", "scans", "mesh_aligned_0.05.ply"))
    doc = scan(nomesh, "dslr", validator)
    assert any(w.startswith("no mesh (scans/mesh_aligned_0.05.ply is missing)")
               for w in doc["scenes"][0]["warnings"]), doc["scenes"][0]["warnings"]
    # render and a pair from the mesh name the file that is missing.
    missing = os.path.join(nomesh, "data", "synthpp_000", "scans", "mesh_aligned_0.05.ply")
    r = common.occgt("render", "--root", nomesh, "--format", "scannetpp", "--scene",
                     "synthpp_000", "--out", os.path.join(nomesh, "render"), check=False)
    assert r.returncode == 2 and r.stderr == (
        f"occgt: error: --mesh: scene synthpp_000 has no mesh of its own ({missing} is "
        "missing): give one\n"), r.stderr
    r = common.occgt("pair", "--root", nomesh, "--format", "scannetpp", "--scene", "synthpp_000",
                     "--frames", "DSC00010,DSC00020", "--depth-source", "mesh", "--out",
                     os.path.join(nomesh, "pair"), check=False)
    assert r.returncode == 1 and f"({missing} is missing)" in r.stderr, r.stderr
    # A scene without a usable frame: render says why (it wrote an empty render.json, exit 0).
    shutil.rmtree(os.path.join(nomesh, "data", "synthpp_000", "dslr", "resized_images"))
    r = common.occgt("render", "--root", nomesh, "--format", "scannetpp", "--scene",
                     "synthpp_000", "--mesh", os.path.join(scene, "scans", "mesh_aligned_0.05.ply"),
                     "--out", os.path.join(nomesh, "render"), check=False)
    assert r.returncode == 1 and re.match(
        r"occgt: error: synthpp_000: no usable frame to render \(\d+ unusable; the first, "
        r"DSC00010: colour: missing file; .*DSC00010.JPG; occgt scan lists them all\)\n$",
        r.stderr), r.stderr
    assert not os.path.exists(os.path.join(nomesh, "render", "render.json"))
    # A DSLR pair with sensor depth (there is none): the frame is named, with what to do.
    r = common.occgt("pair", "--root", root, "--format", "scannetpp", "--scene", "synthpp_000",
                     "--frames", "DSC00010,DSC00020", "--out", os.path.join(root, "pair_dslr"),
                     check=False)
    assert r.returncode == 1 and r.stderr.startswith(
        "occgt: error: frame DSC00010: depth: the frame has no depth file"), r.stderr
    # Bad device: a usage error naming the flag.
    r = common.occgt("scan", root, "--format", "scannetpp", "--device", "kinect", check=False)
    assert r.returncode != 0 and "--device" in r.stderr, r.stderr

    # A recipe reading the iPhone frames.
    build_and_check(root, "iphone", "[128, 96]", "", export=True)
    # The DSLR: depth rendered from the mesh in the undistorted camera, in the shards and in
    # the DUSt3R export (which has no depth file to read).
    out = build_and_check(root, "dslr", "[160, 120]", "  depth_source: mesh\n", export=True)
    check_dslr_export_depth(scene, os.path.join(out, "dust3r"))
    check_selected_pairs(os.path.join(out, "dust3r"))
    check_render_equals_export(root, os.path.join(out, "dust3r", "synthpp_000", "depth"))
    # The shipped recipe (DSLR, depth_source mesh) on the fixture: it builds, and its DUSt3R
    # export reads back.
    shipped = os.path.join(root, "out_shipped")
    common.occgt("build", os.path.join(common.SOURCE, "recipes", "scannetpp-dust3r.yaml"),
                 "--root", root, "--out", shipped)
    posed = occgt_samples(shipped)
    assert posed, "the shipped recipe selects no pair on the fixture"
    posed_readers.check_dust3r("scannetpp shipped recipe", shipped, posed,
                               posed_readers.shard_images(shipped, posed))
    check_selected_pairs(os.path.join(shipped, "dust3r"))

    # One iPhone colour file that is not an image (behind the lens, as every ScanNet++
    # frame): skipped and named at the scan (scan.color_error); it used to stop the build
    # in its write stage.
    broken = common.scratch("scannetpp_broken_colour")
    shutil.copytree(os.path.join(root, "data"), os.path.join(broken, "data"))
    rgb = os.path.join(broken, "data", "synthpp_000", "iphone", "rgb")
    bad = sorted(os.listdir(rgb))[1]
    with open(os.path.join(rgb, bad), "wb") as f:
        f.write(b"garbage")
    with open(os.path.join(root, "iphone.yaml")) as f:
        text = f.read()
    assert text.count(f"root: {root}\n") == 1, text
    with open(os.path.join(broken, "iphone.yaml"), "w") as f:
        f.write(text.replace(f"root: {root}\n", f"root: {broken}\n"))
    out = os.path.join(broken, "out")
    common.occgt("build", os.path.join(broken, "iphone.yaml"), "--out", out)
    with open(os.path.join(out, "summary.json")) as f:
        summary = json.load(f)
    assert summary["drops"].get("scan.color_error") == 1, summary["drops"]
    example = summary["drop_examples"]["scan.color_error"]
    assert example.startswith("synthpp_000/") and bad in example, example


def read_box_mesh(path):
    """The fixture's PLY (binary LE: float x, y, z, uchar r, g, b; faces list uchar int) as
    triangles [T, 3, 3]."""
    with open(path, "rb") as f:
        data = f.read()
    head, body = data.split(b"end_header\n", 1)
    counts = {}
    for line in head.decode().splitlines():
        if line.startswith("element"):
            _, name, n = line.split()
            counts[name] = int(n)
    vdt = np.dtype([("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("rgb", "u1", 3)])
    fdt = np.dtype([("n", "u1"), ("i", "<i4", 3)])
    nv, nf = counts["vertex"], counts["face"]
    assert len(body) == nv * vdt.itemsize + nf * fdt.itemsize, (len(body), nv, nf)
    v = np.frombuffer(body, vdt, nv)
    faces = np.frombuffer(body, fdt, nf, offset=nv * vdt.itemsize)
    assert (faces["n"] == 3).all()
    xyz = np.stack([v["x"], v["y"], v["z"]], axis=1).astype(np.float64)
    return xyz[faces["i"]]


def ray_cast_depth(tris, K, world_from_cam, width, height, near=0.05, far=20.0):
    """Planar depth by brute force (Moller-Trumbore over every triangle), pixel centres at
    integer coordinates (GROUND_TRUTH.md section 1); 0 = no hit in [near, far]."""
    u, v = np.meshgrid(np.arange(width, dtype=np.float64), np.arange(height, dtype=np.float64))
    d_cam = np.stack([(u - K[0, 2]) / K[0, 0], (v - K[1, 2]) / K[1, 1], np.ones_like(u)], -1)
    d = d_cam.reshape(-1, 3) @ world_from_cam[:3, :3].T  # z_cam = 1: t is the planar depth
    o = world_from_cam[:3, 3]
    best = np.full(len(d), np.inf)
    for a, b, c in tris:
        e1, e2 = b - a, c - a
        p = np.cross(d, e2)
        det = p @ e1
        ok = np.abs(det) > 1e-12
        inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
        s = o - a
        bu = (p @ s) * inv
        q = np.cross(s, e1)
        bv = (d @ q) * inv
        t = (q @ e2) * inv
        hit = ok & (bu >= 0) & (bv >= 0) & (bu + bv <= 1) & (t >= near) & (t <= far)
        best = np.where(hit & (t < best), t, best)
    best[~np.isfinite(best)] = 0
    return best.reshape(height, width)


def undistorted_mask(scene, image_name, K, width, height):
    """The fixture's anonymisation mask (0 = anonymised) in the export's pinhole camera,
    nearest-neighbour through OpenCV's fisheye model."""
    with open(os.path.join(scene, "dslr", "colmap", "cameras.txt")) as f:
        cam = [line.split() for line in f if line.strip() and not line.startswith("#")][0]
    fx, fy, cx, cy, k1, k2, k3, k4 = map(float, cam[4:12])
    # COLMAP's pixel centres are at +0.5; OpenCV's at integers.
    Kd = np.array([[fx, 0, cx - 0.5], [0, fy, cy - 0.5], [0, 0, 1]])
    mask = cv2.imread(os.path.join(scene, "dslr", "resized_anon_masks", image_name + ".png"),
                      cv2.IMREAD_GRAYSCALE)
    assert mask is not None, image_name
    mx, my = cv2.fisheye.initUndistortRectifyMap(Kd, np.array([k1, k2, k3, k4]), np.eye(3),
                                                 K, (width, height), cv2.CV_32FC1)
    return cv2.remap(mask, mx, my, cv2.INTER_NEAREST, borderMode=cv2.BORDER_CONSTANT,
                     borderValue=0)


def check_dslr_export_depth(scene, dust3r):
    """Every exported DSLR depth PNG: uint16 mm equal to the exact depth rounded (within half
    a millimetre plus float precision) where the mask keeps the pixel, 0 where it is
    anonymised (pixels 2 away from the mask's edges, whose resampling may differ)."""
    tris = read_box_mesh(os.path.join(scene, "scans", "mesh_aligned_0.05.ply"))
    with np.load(os.path.join(dust3r, "all_metadata.npz")) as m:
        images, K, T = m["images"], m["intrinsics"], m["trajectories"]
        folder = str(m["scenes"][0])
    with np.load(os.path.join(dust3r, folder, "selected_pairs.npz")) as sp:
        stems = sp["selection"]
    assert len(stems) == len(images), (stems, images)
    kernel = np.ones((5, 5), np.uint8)
    anonymised_total = compared_total = 0
    for i, name in enumerate(images):
        raw = cv2.imread(os.path.join(dust3r, folder, "depth", str(name) + ".png"),
                         cv2.IMREAD_UNCHANGED)
        assert raw is not None and raw.dtype == np.uint16, name
        h, w = raw.shape
        exact = ray_cast_depth(tris, K[i], T[i], w, h)
        mask = undistorted_mask(scene, str(stems[i]), K[i], w, h)
        keep = cv2.erode((mask == 255).astype(np.uint8), kernel).astype(bool)
        anonymised = cv2.erode((mask < 255).astype(np.uint8), kernel).astype(bool)
        anonymised &= exact > 0
        assert not raw[anonymised].any(), (name, int(np.count_nonzero(raw[anonymised])))
        sel = keep & (exact > 0)
        err = np.abs(raw[sel] / 1000.0 - exact[sel])
        bad = err > 0.0005 + 1e-4
        # Rays grazing a box edge may hit either face: at most a few such pixels.
        assert bad.sum() <= 0.002 * sel.size, (name, int(bad.sum()), float(err.max()))
        assert sel.sum() > 0.5 * raw.size, (name, int(sel.sum()))
        anonymised_total += int(anonymised.sum())
        compared_total += int(sel.sum())
    # The fixture anonymises a rectangle in every other DSLR image.
    assert anonymised_total > 0, anonymised_total
    print("scannetpp dslr export depth:", compared_total, "pixels equal to the exact depth,",
          anonymised_total, "anonymised pixels 0")


def check_render_equals_export(root, depth_dir):
    """`occgt render` of the exported frames at the export's size writes the export's depth
    PNGs (EXPORTS.md): anonymised pixels 0 in both (render kept the mesh's depth there)."""
    names = sorted(n[:-4] for n in os.listdir(depth_dir))
    out = os.path.join(root, "render_dslr")
    common.occgt("render", "--root", root, "--format", "scannetpp", "--scene", "synthpp_000",
                 "--frames", ",".join(names), "--resolution", "160x120", "--out", out)
    zeros = 0
    for name in names:
        want = cv2.imread(os.path.join(depth_dir, name + ".png"), cv2.IMREAD_UNCHANGED)
        got = cv2.imread(os.path.join(out, name + "_depth.png"), cv2.IMREAD_UNCHANGED)
        assert got is not None and np.array_equal(got, want), name
        ids = np.load(os.path.join(out, name + "_triangles.npy"))
        assert np.array_equal(ids < 0, got == 0), name  # no depth, no triangle
        zeros += int((got == 0).sum())
    assert zeros > 0, zeros


def check_selected_pairs(dust3r):
    """scene_list.json and <scene>/selected_pairs.npz as DUSt3R's ScanNet++ preprocessing reads
    them (selection = image stems, pairs rows (i, j, score)) with occgt's overlaps, matching
    scene_metadata.npz."""
    with open(os.path.join(dust3r, "scene_list.json")) as f:
        scenes = json.load(f)
    with open(os.path.join(common.SOURCE, "schemas", "dust3r_scene_list.schema.json")) as f:
        jsonschema.validate(scenes, json.load(f))
    with np.load(os.path.join(dust3r, "all_metadata.npz")) as m:
        assert scenes == [str(s) for s in m["scenes"]], (scenes, m["scenes"])
    for scene in scenes:
        with np.load(os.path.join(dust3r, scene, "selected_pairs.npz")) as sp, \
                np.load(os.path.join(dust3r, scene, "scene_metadata.npz")) as sm:
            assert sp["selection"].dtype.kind == "U", sp["selection"].dtype
            assert all(str(s).startswith("DSC") for s in sp["selection"]), sp["selection"]
            assert len(sp["selection"]) == len(sm["images"])
            pairs, overlaps = sp["pairs"], sp["overlaps"]
            assert pairs.shape == (len(sm["pairs"]), 3) and overlaps.shape == (len(pairs), 2)
            assert np.array_equal(pairs, sm["pairs"][:, :3]), (pairs, sm["pairs"])
            assert np.array_equal(overlaps, sm["pairs"][:, 3:]), (overlaps, sm["pairs"])
            idx = pairs[:, :2].astype(int)
            assert (idx >= 0).all() and (idx < len(sp["selection"])).all(), idx


def build_and_check(root, device, resolution, extra, export):
    recipe = os.path.join(root, device + ".yaml")
    with open(recipe, "w") as f:
        f.write(f"""name: spp
split: spp
seed: 0
resolution: {resolution}
dataset:
  format: scannetpp
  root: {root}
  device: {device}
{extra}  min_valid_depth_fraction: 0.3
labels:
  preset: default
selection:
  max_frame_gap: 4
  pruning: {{max_distance_m: 3.0, max_view_angle_deg: 90, frustum: true}}
  score_stride: 4
  overlap: [0.05, 1.0]
  occlusion: [0.0, 1.0]
  aggregate: mean
  quota_per_scene: 4
occupancy:
  enabled: false
sample: {{image: png, depth: true, labels: true, occupancy: false}}
shards: {{samples_per_shard: 8}}
dust3r_export: {"true" if export else "false"}
""")
    out = os.path.join(root, "out_" + device)
    common.occgt("build", recipe, "--out", out)
    with open(os.path.join(out, "summary.json")) as f:
        summary = json.load(f)
    shards = sorted(p for p in os.listdir(out) if p.endswith(".tar"))
    assert shards, os.listdir(out)
    samples = read_shard(os.path.join(out, shards[0]))
    assert samples, shards
    for key, members in samples.items():
        assert "image0.png" in members and "depth0.npy" in members, (key, sorted(members))
        depth = np.load(io.BytesIO(members["depth0.npy"]))
        assert depth.dtype == np.float32 and depth.shape == tuple(
            reversed(json.loads(resolution))), depth.shape
        assert (depth > 0).mean() > 0.5, key
    # The DUSt3R ScanNet++ export of the same build, read back by the reader written from
    # DUSt3R's ScanNetpp dataset class (posed_readers.py): K, poses, depth in mm (0 on
    # anonymised pixels, as the shard's depth), images, scores.
    if export:
        posed = occgt_samples(out)
        posed_readers.check_dust3r("scannetpp " + device, out, posed,
                                   posed_readers.shard_images(out, posed))
    print("scannetpp", device + ":", summary.get("samples"), "samples in", len(shards),
          "shard(s)")
    return out


if __name__ == "__main__":
    main()
