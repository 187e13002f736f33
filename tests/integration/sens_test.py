"""ScanNet raw .sens read in place (libgt/datasets/sens.h): the same frames written as a .sens and
in the exporter's layout (tests/support/write_sens.py) give the same scan (poses, K, usable
frames and reasons) and bit-identical `occgt pair` outputs, for a synthetic scene (JPEG colour,
a lost-tracking frame) and the real 7-Scenes sample frames (PNG colour); damaged files are one
line naming the file and the field."""
import json
import os
import struct
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
import common  # noqa: E402

sys.path.insert(0, os.path.join(common.SOURCE, "tests", "support"))
import write_sens  # noqa: E402

out = common.scratch("sens")
write_sens.main(["", "synthetic", out])
write_sens.main(["", "sevenscenes", common.shared("sevenscenes"), out])
sens_root, export_root = os.path.join(out, "sens"), os.path.join(out, "export")


def scan(root, *extra):
    return json.loads(common.occgt("scan", root, "--format", "scannet", "--json", *extra).stdout)


# scan: the same scenes, frame counts, usable counts, reasons and cameras; depth readable.
a, b = scan(sens_root, "--check-depth"), scan(export_root, "--check-depth")
assert [s["name"] for s in a["scenes"]] == ["seven", "synth"], a["scenes"]
for sa, sb in zip(a["scenes"], b["scenes"]):
    for key in sa:
        if key == "unusable_examples":  # the same frames; each detail names its own file
            frames = [{r: [x["frame"] for x in v] for r, v in s[key].items()} for s in (sa, sb)]
            assert frames[0] == frames[1], (sa["name"], frames)
        elif key != "path":
            assert sa[key] == sb[key], (sa["name"], key, sa[key], sb[key])
synth = a["scenes"][1]
assert synth["frames"] == 5 and synth["usable"] == 4, synth
lost = "pose: non-finite pose entries (lost tracking)"
sens_file = os.path.join(sens_root, "synth", "synth.sens")
assert synth["unusable_examples"] == {
    lost: [{"frame": "2", "detail": sens_file + ": frame 2: non-finite value"}]}, synth
assert b["scenes"][1]["unusable_examples"][lost][0]["detail"] == \
    os.path.join(export_root, "synth", "pose", "2.txt") + ":1: non-finite value", b["scenes"][1]
text = common.occgt("scan", sens_root, "--format", "scannet").stdout
assert f"unusable 1: {lost}\n    frame 2: {sens_file}: frame 2: non-finite value\n" in text, text

# pair: every output file bit for bit (labels, matches, meta.json with its K and poses).
for scene, frames, res in [("seven", "0,10", "320x240"), ("seven", "5,40", "160x120"),
                           ("synth", "0,3", "80x60")]:
    outs = []
    for root in [sens_root, export_root]:
        d = os.path.join(out, "pair", os.path.basename(root), scene + frames.replace(",", "_"))
        common.occgt("pair", "--root", root, "--format", "scannet", "--scene", scene, "--frames",
                     frames, "--out", d, "--resolution", res)
        outs.append(d)
    names = sorted(os.listdir(outs[0]))
    assert names == sorted(os.listdir(outs[1])) and "label01.npy" in names, names
    for n in names:
        with open(os.path.join(outs[0], n), "rb") as f0, open(os.path.join(outs[1], n), "rb") as f1:
            assert f0.read() == f1.read(), (scene, frames, n)
    assert (np.load(os.path.join(outs[0], "label01.npy")) == 2).any()  # some VISIBLE pixels

# build: the shards (colour PNG from the .sens JPEG/PNG payloads, depth, labels) and the
# index are byte-identical; only recipe.json (its root) and summary.json (timings) differ.
builds = []
for root in [sens_root, export_root]:
    recipe = os.path.join(out, os.path.basename(root) + ".yaml")
    with open(recipe, "w") as f:
        f.write(f"""name: sens-eq
split: sens-eq
seed: 0
resolution: [320, 240]
dataset: {{format: scannet, root: {root}, scenes: [seven], frame_stride: 2,
          min_valid_depth_fraction: 0.3}}
labels: {{preset: default}}
patches: {{stride: 8, anchor: center, mutual: true}}
selection:
  max_frame_gap: 6
  pruning: {{max_distance_m: 2.0, max_view_angle_deg: 60, frustum: true}}
  score_stride: 8
  overlap: [0.4, 0.9]
  occlusion: [0.0, 1.0]
  aggregate: mean
  quota_per_scene: 4
occupancy: {{enabled: false}}
sample: {{image: png, depth: true, labels: true, occupancy: false}}
shards: {{samples_per_shard: 4}}
loftr_export: {{kind: train, tree: true}}
""")
    d = os.path.join(out, "build_" + os.path.basename(root))
    common.occgt("build", recipe, "--out", d)
    builds.append(d)
files = sorted(os.path.relpath(os.path.join(dp, n), builds[0])
               for dp, _, names in os.walk(builds[0]) for n in names)
assert any(f.endswith(".tar") for f in files), files
import cv2  # noqa: E402
for rel in files:
    if rel in ("recipe.json", "summary.json"):
        continue
    if rel == os.path.join("loftr", "tree.json"):
        t0, t1 = (json.load(open(os.path.join(b, rel))) for b in builds)
        assert t0["linked"] == 0 and t0["converted"] == t1["converted"] + t1["linked"] > 0, (t0, t1)
        continue
    if rel.startswith(os.path.join("loftr", "data") + os.sep) and rel.endswith((".jpg", ".png")):
        # The LoFTR tree links the exported layout's files but decodes the .sens payloads
        # and encodes them again: equal depth values, colour within JPEG re-encoding.
        a = cv2.imread(os.path.join(builds[0], rel), cv2.IMREAD_UNCHANGED)
        b = cv2.imread(os.path.join(builds[1], rel), cv2.IMREAD_UNCHANGED)
        assert a is not None and b is not None and a.shape == b.shape and a.dtype == b.dtype, rel
        if rel.endswith(".png"):
            assert (a == b).all(), rel
        else:
            assert np.abs(a.astype(int) - b.astype(int)).mean() < 3.0, rel
        continue
    with open(os.path.join(builds[0], rel), "rb") as f0, open(os.path.join(builds[1], rel), "rb") as f1:
        assert f0.read() == f1.read(), rel
with open(os.path.join(builds[0], "summary.json")) as f:
    assert json.load(f)["samples"] == 4

# A lost-tracking frame is refused as the exported layout refuses it.
r = common.occgt("pair", "--root", sens_root, "--format", "scannet", "--scene", "synth",
                 "--frames", "0,2", "--out", os.path.join(out, "pair_lost"), check=False)
assert r.returncode != 0 and "lost tracking" in r.stderr, r.stderr
assert r.stderr.rstrip().endswith(": frame 2 is unusable: " + lost + "; " + sens_file +
                                  ": frame 2: non-finite value"), r.stderr

# Damaged files: one line naming the .sens and the field, no crash, no huge allocation.
with open(os.path.join(sens_root, "synth", "synth.sens"), "rb") as f:
    good = f.read()
header_len = len(write_sens.header_bytes(np.eye(3), np.eye(3), (1, 1), (1, 1), 0))
# colorCompression, depthCompression, 4 uint32 sizes, depthShift, numFrames end the header.
fields = header_len - (4 + 4 + 16 + 4 + 8)
frame0 = header_len
color_bytes0 = struct.unpack_from("<Q", good, frame0 + 64 + 16)[0]


def patched(offset, fmt, value):
    b = bytearray(good)
    struct.pack_into(fmt, b, offset, value)
    return bytes(b)


cases = [
    ("cut in the header", good[:50], "colour intrinsic: file ends at byte 50"),
    ("cut in a payload", good[: frame0 + 96 + color_bytes0 // 2], "frame 0: colorBytes"),
    ("frame count too large", patched(header_len - 8, "<Q", 10**9), "numFrames: 1000000000"),
    ("byte count past the end", patched(frame0 + 64 + 24, "<Q", 2**60),
     "run past the end of the file"),
    ("absurd width", patched(fields + 8, "<I", 10**7), "colorWidth: 10000000"),
    ("absurd size", good[:fields + 16] + struct.pack("<II", 60000, 60000) + good[fields + 24:],
     "depth 60000x60000: implausible size"),
    ("OCCI depth", patched(fields + 4, "<i", 2), "depthCompression: 2 (OCCI, proprietary)"),
    ("unknown colour", patched(fields, "<i", -1), "colorCompression: -1 is not supported"),
    ("version", patched(0, "<I", 3), "version: 3, expected 4"),
]
for what, data, expected in cases:
    scene = os.path.join(out, "bad", "s")
    os.makedirs(scene, exist_ok=True)
    path = os.path.join(scene, "s.sens")
    with open(path, "wb") as f:
        f.write(data)
    r = common.occgt("scan", scene, "--format", "scannet", check=False)
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 1 and len(lines) == 1, (what, r.returncode, r.stderr)
    assert path in lines[0] and expected in lines[0], (what, lines[0])
    os.remove(path)

# A corrupt zlib payload is found when the depth is read: one line from pair.
b = bytearray(good)
depth0 = frame0 + 96 + color_bytes0
b[depth0 + 10: depth0 + 30] = b"\xff" * 20
scene = os.path.join(out, "bad", "z")
os.makedirs(scene, exist_ok=True)
with open(os.path.join(scene, "z.sens"), "wb") as f:
    f.write(bytes(b))
r = common.occgt("pair", "--root", scene, "--format", "scannet", "--scene", "z", "--frames", "0,1",
                 "--out", os.path.join(out, "pair_z"), check=False)
lines = r.stderr.strip().splitlines()
assert r.returncode == 1 and len(lines) == 1 and "z.sens: frame 0 (depth payload at byte" in lines[0], \
    r.stderr
print("sens: ok")
