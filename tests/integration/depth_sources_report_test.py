"""Depth sources after a build (issue #33): the split report's sensor-vs-mesh shares, the
depth panels of `inspect pair`, and the ScanNet++ device a build records.

1. A 7-Scenes sample build with dataset.depth_source fused and the shared TSDF mesh:
   `occgt inspect split` writes depth_sources.json (schema) whose per-split and per-scene
   shares equal the per-frame shares of `occgt scan --mesh --json` summed here over the
   distinct frames of pairs.jsonl (the same computation, aggregated independently).
2. `occgt inspect pair` on that scene with the mesh writes depth.png: per frame sensor |
   rendered | fused | agreement. Checked against the depth files read here: the sensor panel
   is black exactly where the sensor has no depth, the rendered panel fills many of those
   holes, the fused panel takes the rendered value there and the sensor's where they agree;
   stdout names the labels' depth source.
3. ScanNet++ (occgt synth --layout scannetpp): a build of each device is re-read with the
   device its recipe.json records (`occgt pair --recipe` reproduces the shard's labels byte
   for byte, `inspect split` re-opens its frames, an `occgt pair` folder's meta.json records
   the device and `inspect pair --pair-dir --root` uses it); a device that contradicts the
   recorded one is refused with one error line. `occgt covis` and `occgt tuples --shards` of
   the same recipe read the frames as the build does: every N-view sample's depth of a frame
   the build also wrote is the build's, byte for byte.
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

sys.path.insert(0, os.path.dirname(__file__))
import common  # noqa: E402

CLASSES = ("sensor_only", "mesh_only", "agree", "disagree", "neither")


def schema(name):
    with open(os.path.join(common.SOURCE, "schemas", name)) as f:
        return json.load(f)


def pairs_lines(build):
    with open(os.path.join(build, "pairs.jsonl")) as f:
        return [json.loads(line) for line in f if line.strip()]


def counts_of(record):
    """The pixel counts of an agreement record (truth::DepthAgreementJson, as render.json's
    sensor), checked against its pixels and its shares."""
    counts = {c: record[c] for c in CLASSES}
    assert all(isinstance(v, int) for v in counts.values()), record
    assert sum(counts.values()) == record["pixels"], record
    for c in CLASSES[:4]:
        assert abs(record["shares"][c] - counts[c] / max(record["pixels"], 1)) < 1e-12, record
    return counts | {"pixels": record["pixels"]}


def check_split_report(root, mesh, tmp):
    recipe = os.path.join(tmp, "fused.yaml")
    with open(recipe, "w") as f:
        f.write(f"""name: fused
split: fused
seed: 0
resolution: [640, 480]
dataset:
  format: sevenscenes
  root: {root}
  frame_stride: 5
  depth_source: fused
  mesh_path: {mesh}
  fused_depth: {{abs_tol_m: 0.05, rel_tol: 0.01}}
selection:
  max_frame_gap: 4
  pruning: {{max_distance_m: 2.0, max_view_angle_deg: 60, frustum: true}}
  score_stride: 8
  overlap: [0.2, 1.0]
  occlusion: [0.0, 1.0]
  quota_per_scene: 5
occupancy:
  enabled: false
sample: {{image: png, depth: true, labels: true, occupancy: false}}
""")
    build = os.path.join(tmp, "build")
    common.occgt("build", recipe, "--out", build)
    lines = pairs_lines(build)
    assert len(lines) >= 2, lines
    r = common.occgt("inspect", "split", build, "--out", os.path.join(tmp, "report"), "--gallery", "0")
    assert "depth source fused" in r.stdout, r.stdout
    with open(os.path.join(tmp, "report", "depth_sources.json")) as f:
        doc = json.load(f)
    jsonschema.validate(doc, schema("split_depth_sources.schema.json"))
    with open(os.path.join(tmp, "report", "report.html")) as f:
        assert "<h2>Depth sources</h2>" in f.read()

    # Independently: scan's per-frame shares (depth camera 640x480 = the build's resolution),
    # same tolerance, summed over the distinct frames of the pairs.
    scan = json.loads(common.occgt("scan", root, "--format", "sevenscenes", "--mesh", mesh,
                                   "--abs-tol-m", "0.05", "--rel-tol", "0.01", "--json").stdout)
    per_frame = {}
    for s in scan["scenes"]:
        for fr in s["mesh_depth"]["frames"]:
            per_frame[(s["name"], fr["id"])] = counts_of(fr)
    frames = sorted({(l["scene"], l[k]["id"]) for l in lines for k in ("frame0", "frame1")})
    want = {c: 0 for c in (*CLASSES, "pixels")}
    for key in frames:
        for c in want:
            want[c] += per_frame[key][c]
    assert doc["source"] == "fused" and doc["tolerance"] == {"abs_tol_m": 0.05, "rel_tol": 0.01}, doc
    assert doc["resolution"] == [640, 480] and doc["frames"] == len(frames), (doc, len(frames))
    assert doc["total"]["pixels"] == want["pixels"] == 640 * 480 * len(frames), doc["total"]
    got = counts_of(doc["total"])
    assert got == want, (got, want)
    assert len(doc["scenes"]) == 1 and counts_of(doc["scenes"][0]) == want, doc["scenes"]
    # The sample has holes the mesh fills and, at 5 cm, some disagreement.
    assert want["mesh_only"] > 0 and want["agree"] > 0.5 * want["pixels"], want
    print("split report: fused shares of", len(frames), "frames equal scan's:",
          {c: round(doc["total"]["shares"][c], 4) for c in CLASSES[:4]})

    # A root that does not hold is one error line naming it.
    r = common.occgt("inspect", "split", build, "--out", os.path.join(tmp, "report2"),
                     "--root", os.path.join(tmp, "nowhere"), check=False)
    assert r.returncode == 1 and len(r.stderr.strip().splitlines()) == 1 and "nowhere" in r.stderr, r.stderr
    return build


def check_inspect_pair(root, mesh, tmp):
    out = os.path.join(tmp, "pair")
    ids = ("000150", "000175")
    r = common.occgt("inspect", "pair", "--root", root, "--format", "sevenscenes", "--scene",
                     "rgbd-frames", "--frames", ",".join(ids), "--mesh", mesh, "--depth-source",
                     "fused", "--no-occupancy", "--out", out)
    assert "labels from depth source fused" in r.stdout, r.stdout
    pic = cv2.imread(os.path.join(out, "depth.png"), cv2.IMREAD_COLOR)
    assert pic is not None
    w, h, gap, title = 640, 480, 8, 22  # panels at the working resolution, pictures.h's gap
    assert pic.shape[1] == 4 * w + 3 * gap and pic.shape[0] > 2 * (h + title), pic.shape
    for row, fid in enumerate(ids):
        y0 = row * (h + title) + title

        def panel(k):
            x0 = k * (w + gap)
            return pic[y0:y0 + h, x0:x0 + w].astype(int)

        sensor, rendered, fused, classes = (panel(k) for k in range(4))
        raw = cv2.imread(os.path.join(root, "rgbd-frames", f"frame-{fid}.depth.png"),
                         cv2.IMREAD_UNCHANGED)
        hole = (raw == 0) | (raw == 65535)  # 7-Scenes' invalid depth
        black = lambda p: (p == 0).all(axis=2)  # noqa: E731
        assert hole.any() and (~hole).any()
        assert np.array_equal(black(sensor), hole), (fid, int((black(sensor) != hole).sum()))
        filled = hole & ~black(rendered)
        assert filled.sum() > 0.2 * hole.sum(), (fid, int(filled.sum()), int(hole.sum()))
        # Fused: the rendered value in the holes, the sensor's where both agree (green).
        assert np.array_equal(fused[filled], rendered[filled]), fid
        green = (classes == (60, 200, 40)).all(axis=2)  # BGR of agree
        assert green.sum() > 0.5 * green.size, (fid, int(green.sum()))
        assert np.array_equal(fused[green], sensor[green]), fid
        # Where they disagree (red), fused has nothing.
        red = (classes == (40, 40, 230)).all(axis=2)
        assert black(fused)[red].all(), fid
        # The panels are different pictures where the sensor has holes.
        assert (sensor[hole] != rendered[hole]).any(), fid
    print("inspect pair: depth.png panels checked on", ids)
    # A dataset without a mesh: no depth.png, the source is still said.
    out2 = os.path.join(tmp, "pair_nomesh")
    r = common.occgt("inspect", "pair", "--root", root, "--format", "sevenscenes", "--scene",
                     "rgbd-frames", "--frames", ",".join(ids), "--no-occupancy", "--out", out2)
    assert "labels from depth source sensor" in r.stdout, r.stdout
    assert not os.path.exists(os.path.join(out2, "depth.png"))


def shard_member(build, key, field):
    line = next(l for l in pairs_lines(build) if l["key"] == key)
    with tarfile.open(os.path.join(build, line["shard"])) as tar:
        names = tar.getnames()
        name = key + "." + field
        if name + ".gz" in names:
            return gzip.decompress(tar.extractfile(name + ".gz").read())
        return tar.extractfile(name).read()


def one_line_error(r, code, *words):
    lines = r.stderr.strip().splitlines()
    assert r.returncode == code and len(lines) == 1, (r.returncode, r.stderr)
    for w in words:
        assert w in lines[0], (w, lines[0])


def check_views_depth(recipe, build, out):
    """`occgt covis` and `occgt tuples --shards` read the frames as the build does (the
    recipe's device and depth source): each N-view sample's depth<i>.npy is the build's
    depth of that frame, byte for byte."""
    common.occgt("covis", recipe, "--out", out)
    common.occgt("tuples", recipe, "--out", out, "--shards")
    build_depth = {}
    for line in pairs_lines(build):
        for k in (0, 1):
            build_depth[(line["scene"], line[f"frame{k}"]["id"])] = shard_member(
                build, line["key"], f"depth{k}.npy")
    views = os.path.join(out, "views")
    compared = 0
    for line in pairs_lines(views):
        for i, frame_id in enumerate(line["frame_ids"]):
            want = build_depth.get((line["scene"], frame_id))
            if want is not None:
                got = shard_member(views, line["key"], f"depth{i}.npy")
                assert got == want, (line["key"], frame_id)
                compared += 1
    assert compared > 0, "no frame of a tuple is in the build"
    print(f"views {os.path.basename(out)}: {compared} view depths equal the build's")


def check_scannetpp_device(tmp):
    root = os.path.join(tmp, "spp")
    common.occgt("synth", "--layout", "scannetpp", "--out", root, "--scenes", "1", "--frames",
                 "5", "--resolution", "160x120")
    for device, res, extra in (("dslr", "[160, 120]", "  depth_source: mesh\n"),
                               ("iphone", "[128, 96]", "  depth_source: fused\n")):
        recipe = os.path.join(tmp, device + ".yaml")
        with open(recipe, "w") as f:
            f.write(f"""name: spp
split: spp
resolution: {res}
dataset:
  format: scannetpp
  root: {root}
  device: {device}
{extra}  min_valid_depth_fraction: 0.3
selection:
  max_frame_gap: 4
  pruning: {{max_distance_m: 3.0, max_view_angle_deg: 90, frustum: true}}
  score_stride: 4
  overlap: [0.05, 1.0]
  quota_per_scene: 3
  views: [2, 3]
  tuples: {{edge_threshold: 0.05, quota_per_scene: 3}}
occupancy:
  enabled: false
sample: {{image: png, depth: true, labels: true, occupancy: false}}
""")
        build = os.path.join(tmp, "out_" + device)
        common.occgt("build", recipe, "--out", build)
        check_views_depth(recipe, build, os.path.join(tmp, "views_" + device))
        with open(os.path.join(build, "recipe.json")) as f:
            assert json.load(f)["dataset"]["device"] == device
        line = pairs_lines(build)[0]
        ids = line["frame0"]["id"], line["frame1"]["id"]
        assert ids[0].startswith("frame_") == (device == "iphone"), ids
        # Re-read with the recipe's device: the shard's labels byte for byte.
        pdir = os.path.join(tmp, "pair_" + device)
        common.occgt("pair", "--recipe", recipe, "--scene", line["scene"], "--frames",
                     ",".join(ids), "--out", pdir)
        got = np.load(os.path.join(pdir, "label01.npy"))
        want = np.load(io.BytesIO(shard_member(build, line["key"], "label01.npy")))
        assert np.array_equal(got, want), device
        with open(os.path.join(pdir, "meta.json")) as f:
            meta = json.load(f)
        jsonschema.validate(meta, schema("pair_meta.schema.json"))
        assert meta["device"] == device and meta["depth_source"] == extra.split()[-1], meta
        # The report re-opens the build's frames with the recorded device.
        r = common.occgt("inspect", "split", build, "--out", os.path.join(tmp, "rep_" + device),
                         "--gallery", "0")
        with open(os.path.join(tmp, "rep_" + device, "depth_sources.json")) as f:
            doc = json.load(f)
        assert doc["frames"] == len({(l["scene"], l[k]["id"]) for l in pairs_lines(build)
                                     for k in ("frame0", "frame1")}), doc
        if device == "dslr":  # no depth sensor: every pixel is the mesh's or none
            assert doc["total"]["sensor_only"] == 0 and doc["total"]["agree"] == 0, doc
            assert doc["total"]["shares"]["mesh_only"] > 0.5, doc
        else:  # the fixture's iPhone depth is the scene's own: mostly agreeing
            assert doc["total"]["agree"] > 0.5, doc
        # The pair folder read back under the root with meta.json's device.
        r = common.occgt("inspect", "pair", "--pair-dir", pdir, "--root", root, "--out",
                         os.path.join(tmp, "insp_" + device))
        assert "(no colour images)" not in r.stdout, r.stdout

        # Mismatches: one line each.
        other = "iphone" if device == "dslr" else "dslr"
        r = common.occgt("pair", "--recipe", recipe, "--device", other, "--scene", line["scene"],
                         "--frames", ",".join(ids), "--out", os.path.join(tmp, "x"), check=False)
        one_line_error(r, 2, "--device", "dataset.device")
        meta["device"] = other
        with open(os.path.join(pdir, "meta.json"), "w") as f:
            json.dump(meta, f)
        r = common.occgt("inspect", "pair", "--pair-dir", pdir, "--root", root, "--out",
                         os.path.join(tmp, "x2"), check=False)
        one_line_error(r, 1, "meta.json", ids[0], other)
        with open(os.path.join(build, "recipe.json")) as f:
            rj = json.load(f)
        rj["dataset"]["device"] = other
        with open(os.path.join(build, "recipe.json"), "w") as f:
            json.dump(rj, f)
        r = common.occgt("inspect", "split", build, "--out", os.path.join(tmp, "x3"), check=False)
        one_line_error(r, 1, "recipe.json", "dataset.device", other)
        # An old recipe.json without the device: refused, naming the field.
        del rj["dataset"]["device"]
        with open(os.path.join(build, "recipe.json"), "w") as f:
            json.dump(rj, f)
        r = common.occgt("inspect", "split", build, "--out", os.path.join(tmp, "x4"), check=False)
        one_line_error(r, 1, "dataset.device", "missing")
        print("scannetpp", device + ": re-read with the recorded device; mismatches refused")


def main():
    tmp = common.scratch("depth_sources_report")
    root = common.shared("sevenscenes")
    mesh = common.shared("meshes/sevenscenes-rgbd-frames-tsdf.ply")
    check_split_report(root, mesh, tmp)
    check_inspect_pair(root, mesh, tmp)
    check_scannetpp_device(tmp)


if __name__ == "__main__":
    main()
