"""ScanNet++ end to end on occgt's own fixture (occgt synth --layout scannetpp): the files are
ScanNet++'s (COLMAP text models with an OPENCV_FISHEYE / OPENCV camera and COLMAP's +0.5
principal point, a binary PLY mesh, uint16 depth PNGs, an LZ4-record depth.bin); `occgt scan
--format scannetpp --json` validates against schemas/scan.schema.json and explains every
unusable image for both devices; a recipe with dataset.device iphone builds shards whose
images are the undistorted frames and whose depth has no value on anonymised pixels, and its
DUSt3R ScanNet++ export reads back through a reader written from DUSt3R's dataset class."""
import gzip
import io
import json
import os
import struct
import sys
import tarfile

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
    # The undistorted pinhole camera: principal point (w/2, h/2) in OpenCV's convention.
    assert s["K"]["cx"] == 80.0 and s["K"]["cy"] == 60.0, s["K"]
    iphone = scan(root, "iphone", validator)
    s = iphone["scenes"][0]
    assert s["unusable_reasons"] == {"pose: image not in the COLMAP model": 1}, s
    assert s["depth_size"] == [256, 192], s

    # Bad device: a usage error naming the flag.
    r = common.occgt("scan", root, "--format", "scannetpp", "--device", "kinect", check=False)
    assert r.returncode != 0 and "--device" in r.stderr, r.stderr

    # A recipe reading the iPhone frames.
    build_and_check(root, "iphone", "[128, 96]", "", export=True)
    # The DSLR: depth rendered from the mesh in the undistorted camera (the posed exports
    # read depth files, which the DSLR has not: shards only).
    build_and_check(root, "dslr", "[160, 120]", "  depth_source: mesh\n", export=False)


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


if __name__ == "__main__":
    main()
