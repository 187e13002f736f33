"""occgt scan --json on each real sample: schema-valid output (Draft 2020-12) and the
expected counts; unusable frames counted by a stable reason, the first few listed with
where their problem is ("pose_left.txt:11: non-finite value"); a bad input exits non-zero
with one line naming the file."""
import json
import os
import sys

import jsonschema

sys.path.insert(0, os.path.dirname(__file__))
import common  # noqa: E402

schema = json.load(open(os.path.join(common.SOURCE, "schemas", "scan.schema.json")))
jsonschema.Draft202012Validator.check_schema(schema)
validator = jsonschema.Draft202012Validator(schema)


def scan(root, fmt, *extra):
    r = common.occgt("scan", root, "--format", fmt, "--json", *extra)
    doc = json.loads(r.stdout)
    errors = sorted(validator.iter_errors(doc), key=str)
    assert not errors, f"{fmt}: schema errors: {[e.message for e in errors]}"
    assert doc["format"] == fmt
    t = doc["totals"]
    assert t["frames"] == sum(s["frames"] for s in doc["scenes"])
    assert t["usable"] + t["unusable"] == t["frames"]
    for s in doc["scenes"]:
        assert s["usable"] + s["unusable"] == s["frames"]
        assert sum(s["unusable_reasons"].values()) == s["unusable"]
        for reason, examples in s["unusable_examples"].items():
            assert len(examples) == min(5, s["unusable_reasons"][reason]), (reason, examples)
    return doc


# TartanAir: 24 usable frames, K 320/320/320/240 at 640x480; every depth file read.
doc = scan(common.shared("tartanair/hospital_sample"), "tartanair", "--check-depth")
assert doc["totals"] == {"scenes": 1, "frames": 24, "usable": 24, "unusable": 0,
                         "usable_with_color": 24, "unusable_reasons": {}}, doc["totals"]
s = doc["scenes"][0]
assert s["color"] == {"usable_with_color": 24, "size": [640, 480],
                      "K": [[320, 0, 320], [0, 320, 240], [0, 0, 1]], "uniform_color_camera": True}
assert s["warnings"] == [], s["warnings"]
assert s["depth_size"] == [640, 480] and s["K"] == [[320, 0, 320], [0, 320, 240], [0, 0, 1]]
assert s["depth_check"]["files_read"] == 24 and s["depth_check"]["files_bad"] == 0
assert 0.5 < s["depth_check"]["mean_valid_fraction"] <= 1.0

# 7-Scenes: 50 usable frames, from the sequence folder or its parent.
for root in ("sevenscenes/rgbd-frames", "sevenscenes"):
    doc = scan(common.shared(root), "sevenscenes")
    assert doc["totals"]["usable"] == 50 and doc["totals"]["frames"] == 50, doc["totals"]
    assert doc["scenes"][0]["name"] == "rgbd-frames"
    assert doc["scenes"][0]["K"] == [[585, 0, 320], [0, 585, 240], [0, 0, 1]]
    assert doc["scenes"][0]["color"]["usable_with_color"] == 50
    # The dataset caveat: depth and colour are not registered.
    assert len(doc["scenes"][0]["warnings"]) == 1, doc["scenes"][0]["warnings"]
    assert "unregistered" in doc["scenes"][0]["warnings"][0]
doc = scan(common.shared("sevenscenes/rgbd-frames"), "sevenscenes", "--check-depth")
assert doc["scenes"][0]["depth_check"]["files_read"] == 50

# ScanNet sample: 4 frames, none usable (no depth folder), K from intrinsic_depth.txt.
doc = scan(common.shared("scannet_posed_color/scene_sample"), "scannet")
assert doc["totals"] == {"scenes": 1, "frames": 4, "usable": 0, "unusable": 4, "usable_with_color": 0,
                         "unusable_reasons": {"depth: missing file": 4}}, doc["totals"]
k = doc["scenes"][0]["K"]
assert abs(k[0][0] - 577.590698) < 1e-9 and abs(k[1][2] - 242.683609) < 1e-9

# Colour coverage: a 7-Scenes copy where every other frame lacks its colour file (both
# colour extensions the releases use are accepted: half the rest are .color.jpg).
import shutil  # noqa: E402
src = common.shared("sevenscenes/rgbd-frames")
part = os.path.join(common.scratch("scan_colour"), "seq-01")
os.makedirs(part)
kept = 0
for name in sorted(os.listdir(src)):
    if ".color." in name:
        n = int(name.split("-")[1].split(".")[0])
        if n % 2:
            continue
        if n % 4 == 0:
            name_out = name.replace(".color.png", ".color.jpg")
            shutil.copyfile(os.path.join(src, name), os.path.join(part, name_out))
            kept += 1
            continue
        kept += 1
    os.symlink(os.path.join(src, name), os.path.join(part, name))
doc = scan(part, "sevenscenes")
s = doc["scenes"][0]
assert s["usable"] == 50 and s["color"]["usable_with_color"] == kept == 25, (s["color"], kept)
assert doc["totals"]["usable_with_color"] == 25
assert any(w.startswith("25 of 50 usable frames have no colour image") for w in s["warnings"]), s["warnings"]
text = common.occgt("scan", part, "--format", "sevenscenes").stdout
assert "colour 25 of 50 usable frames" in text and "(25 with colour)" in text, text

# --scene selects one scene by name.
doc = scan(common.shared("scannet_posed_color"), "scannet", "--scene", "scene_sample")
assert [s["name"] for s in doc["scenes"]] == ["scene_sample"]

# Lost tracking is counted, not fatal.
fixtures = os.path.join(common.SOURCE, "tests", "fixtures", "io")
lost = os.path.join(fixtures, "scannet_lost_tracking")
doc = scan(lost, "scannet")
assert doc["totals"]["unusable_reasons"] == {"depth: missing file": 1,
                                             "pose: non-finite pose entries (lost tracking)": 2}
assert doc["scenes"][0]["unusable_examples"] == {
    "depth: missing file": [{"frame": "0", "detail": ""}],
    "pose: non-finite pose entries (lost tracking)": [
        {"frame": n, "detail": os.path.join(lost, "pose", n + ".txt") + ":1: non-finite value"}
        for n in ("7", "12")]}, doc["scenes"][0]["unusable_examples"]

# --check-depth also reads each usable frame's colour header: a colour file that is not an
# image is counted in a warning (it passed as colour, and a build storing images then
# dropped the frame as scan.color_error); the frame stays usable (a build without images
# can use it).
src = common.shared("tartanair/hospital_sample")
bad_color = os.path.join(common.scratch("scan_bad_color"), "P000")
os.makedirs(os.path.join(bad_color, "image_left"))
os.symlink(os.path.join(src, "depth_left"), os.path.join(bad_color, "depth_left"))
os.symlink(os.path.join(src, "pose_left.txt"), os.path.join(bad_color, "pose_left.txt"))
for name in sorted(os.listdir(os.path.join(src, "image_left"))):
    os.symlink(os.path.join(src, "image_left", name), os.path.join(bad_color, "image_left", name))
broken = os.path.join(bad_color, "image_left", "000007_left.png")
os.remove(broken)
with open(broken, "w") as f:
    f.write("not an image\n")
doc = scan(bad_color, "tartanair", "--check-depth")
s = doc["scenes"][0]
assert s["usable"] == 24 and s["color"]["usable_with_color"] == 23, s
assert any(w.startswith("1 usable frame(s) have a colour file whose header cannot be read or "
                        "gives another size than its K's (first: frame 000007: " + broken) and
           w.endswith("a build that stores images skips them (drop scan.color_error)")
           for w in s["warnings"]), s["warnings"]
assert not any("have no colour image" in w for w in s["warnings"]), s["warnings"]
s = scan(bad_color, "tartanair")["scenes"][0]  # without --check-depth: not read
assert s["color"]["usable_with_color"] == 24, s["color"]

# Issue #32: a NaN on line 11 of a TartanAir pose_left.txt (frame 000010) and on the six lines
# after it. Frames are unusable, the scene is not; scan counts one reason and lists the first
# five frames with the file and line; `occgt pair` on frame 000010 says where.
src = common.shared("tartanair/hospital_sample")
nan_traj = os.path.join(common.scratch("scan_nan_pose"), "P000")
os.makedirs(nan_traj)
for name in ("depth_left", "image_left"):
    os.symlink(os.path.join(src, name), os.path.join(nan_traj, name))
pose_lines = open(os.path.join(src, "pose_left.txt")).read().splitlines()
for i in range(10, 17):
    pose_lines[i] = "nan " + " ".join(pose_lines[i].split()[1:])
pose_file = os.path.join(nan_traj, "pose_left.txt")
with open(pose_file, "w") as f:
    f.write("\n".join(pose_lines) + "\n")
doc = scan(nan_traj, "tartanair")
s = doc["scenes"][0]
assert s["frames"] == 24 and s["usable"] == 17, s
assert s["unusable_reasons"] == {"pose: non-finite pose entries": 7}, s["unusable_reasons"]
assert s["unusable_examples"] == {"pose: non-finite pose entries": [
    {"frame": "%06d" % n, "detail": f"{pose_file}:{n + 1}: non-finite value"}
    for n in range(10, 15)]}, s["unusable_examples"]
text = common.occgt("scan", nan_traj, "--format", "tartanair").stdout
assert ("  unusable 7: pose: non-finite pose entries\n"
        f"    frame 000010: {pose_file}:11: non-finite value\n") in text, text
assert f"    frame 000014: {pose_file}:15: non-finite value\n    ... and 2 more\n" in text, text
r = common.occgt("pair", "--root", nan_traj, "--format", "tartanair", "--scene", "P000",
                 "--frames", "000000,000010",
                 "--out", os.path.join(common.scratch("scan_nan_pair"), "out"), check=False)
assert r.returncode == 2, (r.returncode, r.stderr)  # it names a flag: a usage error
assert r.stderr == ("occgt: error: --frames: frame 000010 is unusable: pose: non-finite pose "
                    f"entries; {pose_file}:11: non-finite value\n"), r.stderr

# A malformed per-frame pose file: its frame is unusable (counted, the detail naming the
# file and line), the scan goes on.
for root, frame, detail in [
        ("scannet_short_pose", "1", "pose/1.txt: expected 16 numbers (4x4 matrix), found 12"),
        ("scannet_bad_token", "3", "pose/3.txt:3: expected a number, found 'O.5'")]:
    s = scan(os.path.join(fixtures, root), "scannet")["scenes"][0]
    assert s["unusable_reasons"]["pose: malformed file"] == 1, s["unusable_reasons"]
    assert s["unusable_examples"]["pose: malformed file"] == [
        {"frame": frame, "detail": os.path.join(fixtures, root, detail)}], s["unusable_examples"]

# Bad inputs: exit 1, one line on stderr naming the file, nothing on stdout.
bad = [
    (os.path.join(fixtures, "generic_duplicate_ids"), "generic",
     os.path.join(fixtures, "generic_duplicate_ids", "scene.json")),
    (os.path.join(fixtures, "tartanair_short_pose"), "tartanair",
     os.path.join(fixtures, "tartanair_short_pose", "pose_left.txt")),
    ("/nonexistent/occgt_root", "tum", "/nonexistent/occgt_root"),
]
for root, fmt, named in bad:
    r = common.occgt("scan", root, "--format", fmt, "--json", check=False)
    assert r.returncode == 1, (root, r.returncode, r.stderr)
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and named in lines[0], (root, r.stderr)
    assert r.stdout == "", r.stdout

r = common.occgt("scan", common.shared("sevenscenes"), "--format", "nope", check=False)
assert r.returncode == 2 and r.stderr.startswith("occgt: error: --format: "), r.stderr
assert r.stderr.count("\n") == 1, r.stderr

# --check-depth: a depth file of the wrong size is counted, not fatal.
import numpy as np  # noqa: E402
gen = common.scratch("scan_check_depth")
np.save(os.path.join(gen, "a.npy"), np.full((48, 64), 2.0, np.float32))
np.save(os.path.join(gen, "b.npy"), np.full((24, 32), 2.0, np.float32))
K = [[100, 0, 31.5], [0, 100, 23.5], [0, 0, 1]]
I = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]
frames = [{"id": i, "depth": {"path": i + ".npy", "format": "npy"}, "K": K, "width": 64,
           "height": 48, "world_from_cam": I} for i in ("a", "b", "c")]
json.dump({"format": "occgt-scene-manifest", "version": 1, "scene": "chk", "frames": frames},
          open(os.path.join(gen, "scene.json"), "w"))
doc = scan(gen, "generic", "--check-depth")
s = doc["scenes"][0]
assert s["usable"] == 1 and s["unusable_reasons"] == {
    "depth: missing file": 1, "depth: unreadable or wrong size": 1}, s
assert s["depth_check"]["files_read"] == 1 and s["depth_check"]["files_bad"] == 1
assert "b.npy: depth is 32x24, expected 64x48" in s["depth_check"]["errors"][0]
assert s["depth_check"]["mean_valid_fraction"] == 1.0
assert s["color"] == {"usable_with_color": 0, "size": None, "K": None, "uniform_color_camera": True}
assert any(w.startswith("no usable frame has a colour image") for w in s["warnings"]), s["warnings"]

# docs/CLI.md's scan example runs as written (from the repository root) and prints what it shows.
import re  # noqa: E402
import subprocess  # noqa: E402
cli = open(os.path.join(common.SOURCE, "docs", "CLI.md"), encoding="utf-8").read()
m = re.search(r"Example \(the real TartanAir sample\):\n\n((?:    .*\n)+)", cli)
assert m, "docs/CLI.md: scan example not found"
lines = [ln[4:] for ln in m.group(1).splitlines()]
assert lines[0].startswith("$ occgt scan "), lines[0]
argv = lines[0][2:].split()[1:]
r = subprocess.run([common.BINARY, *argv], cwd=common.SOURCE, capture_output=True, text=True)
assert r.returncode == 0, r.stderr
assert r.stdout.splitlines() == lines[1:], (r.stdout, lines[1:])

# With a mesh, a sensor depth file that cannot be read is skipped by the comparison and
# listed (it stopped the whole scan, without any report).
seven = common.shared("sevenscenes")
cut = common.scratch("scan_mesh_unreadable")
os.makedirs(os.path.join(cut, "rgbd-frames"))
shutil.copyfile(os.path.join(seven, "camera-intrinsics.txt"), os.path.join(cut, "camera-intrinsics.txt"))
names = sorted(os.listdir(os.path.join(seven, "rgbd-frames")))
for name in names[:12]:  # three frames: pose, colour, depth of each
    os.symlink(os.path.join(seven, "rgbd-frames", name), os.path.join(cut, "rgbd-frames", name))
depths = sorted(n for n in os.listdir(os.path.join(cut, "rgbd-frames")) if n.endswith(".depth.png"))
victim = os.path.join(cut, "rgbd-frames", depths[1])
data = open(victim, "rb").read()
os.unlink(victim)
with open(victim, "wb") as f:
    f.write(data[:200])
s = scan(cut, "sevenscenes", "--mesh",
         common.shared("meshes/sevenscenes-rgbd-frames-tsdf.ply"))["scenes"][0]["mesh_depth"]
frame = depths[1][len("frame-"):-len(".depth.png")]
assert [u["id"] for u in s["unreadable"]] == [frame], s["unreadable"]
assert "truncated PNG" in s["unreadable"][0]["error"], s["unreadable"]
assert frame not in {f["id"] for f in s["frames"]} and len(s["frames"]) == len(depths) - 1, s["frames"]
print("scan integration: OK")

# MegaDepth, a scene without a sparse model beside one with it: its depth camera is unknown,
# so depth_size and K are null (they were [0, 0] and a zero K, against the schema), and the
# text says so ("depth 0x0, K fx=0 ...").
md = common.scratch("scan_megadepth_no_model")
for scene in ("0001", "0002"):
    for sub in ("depths", "imgs"):
        os.makedirs(os.path.join(md, scene, "dense0", sub), exist_ok=True)
    open(os.path.join(md, scene, "dense0", "depths", "a.h5"), "wb").close()
os.makedirs(os.path.join(md, "0001", "dense0", "sparse"), exist_ok=True)
with open(os.path.join(md, "0001", "dense0", "sparse", "cameras.txt"), "w") as f:
    f.write("1 PINHOLE 64 48 50 50 32 24\n")
with open(os.path.join(md, "0001", "dense0", "sparse", "images.txt"), "w") as f:
    f.write("1 1 0 0 0 0 0 0 1 a.jpg\n\n")
doc = scan(md, "megadepth")
got = {s["name"]: (s["depth_size"], s["K"]) for s in doc["scenes"]}
assert got == {"0001": ([64, 48], [[50, 0, 31.5], [0, 50, 23.5], [0, 0, 1]]),
               "0002": (None, None)}, got
text = common.occgt("scan", md, "--format", "megadepth").stdout
assert "  depth camera unknown (no frame has one), valid range" in text, text

# A newline in a folder name stays on one line in the text output (as \x0a): a scene's
# detail lines were split in two.
nl = os.path.join(common.scratch("scan_newline"), "nl\nx")
os.makedirs(os.path.join(nl, "pose"), exist_ok=True)
with open(os.path.join(nl, "intrinsic_depth.txt"), "w") as f:
    f.write("50 0 31.5\n0 50 23.5\n0 0 1\n")
os.makedirs(os.path.join(nl, "intrinsic"), exist_ok=True)
os.replace(os.path.join(nl, "intrinsic_depth.txt"), os.path.join(nl, "intrinsic", "intrinsic_depth.txt"))
with open(os.path.join(nl, "pose", "0.txt"), "w") as f:
    f.write("1 0 0 0\n0 1 0 0\n0 0 1 0\n")  # 12 of 16 numbers
text = common.occgt("scan", nl, "--format", "scannet").stdout
detail = [line for line in text.splitlines() if line.startswith("    frame 0: ")]
assert len(detail) == 1 and "nl\\x0ax/pose/0.txt: expected 16 numbers" in detail[0], text
assert not any(line.startswith("x/") for line in text.splitlines()), text
