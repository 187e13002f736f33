"""Rendered depth through the occgt binary on the real 7-Scenes sample with the shared TSDF
mesh (../shared/data, required): `occgt render` (npy, uint16 mm PNG, triangle ids, picture,
render.json against schemas/render.schema.json, the sensor-vs-mesh counts re-counted here),
`occgt pair --depth-source` (sensor by default and byte-identical to no flag; mesh; fused
fills sensor holes), `occgt scan --mesh` (schemas/scan.schema.json, the shares), and bad
flags (exit 2 with one line naming the flag)."""
import json
import os
import signal
import subprocess
import sys
import time

import cv2
import jsonschema
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common  # noqa: E402

ROOT = common.shared("sevenscenes")
MESH = common.shared("meshes/sevenscenes-rgbd-frames-tsdf.ply")
ARGS = ["--root", ROOT, "--format", "sevenscenes", "--scene", "rgbd-frames"]


def schema(name):
    with open(os.path.join(common.SOURCE, "schemas", name)) as f:
        return json.load(f)


def sensor_depth(frame_id):
    raw = cv2.imread(os.path.join(ROOT, "rgbd-frames", f"frame-{frame_id}.depth.png"), cv2.IMREAD_UNCHANGED)
    d = raw.astype(np.float32) / 1000.0
    d[raw == 65535] = 0
    return d


def test_render():
    out = common.scratch("render_cli")
    r = common.occgt("render", *ARGS, "--mesh", MESH, "--frames", "000150,000175", "--out", out)
    assert "render rgbd-frames: 2 frames" in r.stdout, r.stdout
    with open(os.path.join(out, "render.json")) as f:
        doc = json.load(f)
    jsonschema.validate(doc, schema("render.schema.json"))
    assert doc["mesh"] == MESH and doc["tolerance"] == {"abs_tol_m": 0.2, "rel_tol": 0.01}
    for frame in doc["frames"]:
        fid = frame["id"]
        depth = np.load(os.path.join(out, f"{fid}_depth.npy"))
        ids = np.load(os.path.join(out, f"{fid}_triangles.npy"))
        png = cv2.imread(os.path.join(out, f"{fid}_depth.png"), cv2.IMREAD_UNCHANGED)
        picture = cv2.imread(os.path.join(out, f"{fid}_picture.png"))
        assert depth.dtype == np.float32 and depth.shape == (480, 640)
        assert ids.dtype == np.int32 and png.dtype == np.uint16 and picture.shape == (480, 3 * 640, 3)
        assert np.array_equal(ids >= 0, depth > 0)
        assert np.array_equal(png, np.round(depth.astype(np.float64) * 1000).astype(np.uint16))
        assert abs(frame["rendered_fraction"] - float((depth > 0).mean())) < 1e-9
        # The counts of render.json, re-counted from the files (7-Scenes' range 0.1-10 m).
        s = sensor_depth(fid)
        has_s = (s >= 0.1) & (s <= 10.0) & (s > 0)
        has_m = depth > 0
        agree = has_s & has_m & (np.abs(s - depth) <= 0.2 + 0.01 * depth)
        c = frame["sensor"]
        assert c["pixels"] == 640 * 480
        assert c["agree"] == int(agree.sum()), (c, int(agree.sum()))
        assert c["mesh_only"] == int((~has_s & has_m).sum())
        assert c["sensor_only"] == int((has_s & ~has_m).sum())
        assert c["disagree"] == int((has_s & has_m & ~agree).sum())
        assert c["shares"]["agree"] > 0.75 and c["agree"] > 20 * c["disagree"], c
        both = has_s & has_m
        assert np.median(np.abs(s[both] - depth[both])) < 0.01
    # Half resolution: K rescaled, the mesh rendered at that size.
    half = common.scratch("render_cli_half")
    common.occgt("render", *ARGS, "--mesh", MESH, "--frames", "000160", "--resolution", "320x240",
                 "--out", half)
    assert np.load(os.path.join(half, "000160_depth.npy")).shape == (240, 320)
    assert "warning" not in r.stdout, r.stdout
    # A mesh that covers no pixel of any frame (in millimetres, or another world frame: here
    # one triangle 5 km away) is said so (it rendered nothing without a word).
    far = os.path.join(half, "far.ply")
    with open(far, "w") as f:
        f.write("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                "end_header\n5000 0 0\n5001 0 0\n5000 1 0\n3 0 1 2\n")
    r = common.occgt("render", *ARGS, "--mesh", far, "--frames", "000160", "--resolution",
                     "320x240", "--out", os.path.join(half, "far"))
    assert ("warning: the mesh covers no pixel of any frame: is it in metres and in the frames' "
            "world frame (the poses')?") in r.stdout, r.stdout


def meta_counts(folder):
    with open(os.path.join(folder, "meta.json")) as f:
        return json.load(f)["metrics"]["01"]["counts"]


def test_pair_depth_source():
    pair = ARGS + ["--frames", "000150,000160"]
    default = common.scratch("pair_default")
    common.occgt("pair", *pair, "--out", default)
    sensor = common.scratch("pair_sensor")
    common.occgt("pair", *pair, "--depth-source", "sensor", "--mesh", MESH, "--out", sensor)
    for name in sorted(os.listdir(default)):
        if name.endswith(".npy"):
            with open(os.path.join(default, name), "rb") as a, open(os.path.join(sensor, name), "rb") as b:
                assert a.read() == b.read(), name
    counts = {}
    for source in ("mesh", "fused"):
        out = common.scratch("pair_" + source)
        common.occgt("pair", *pair, "--depth-source", source, "--mesh", MESH, "--out", out)
        counts[source] = meta_counts(out)
    counts["sensor"] = meta_counts(default)
    # The mesh fills sensor holes: fewer pixels without depth, more seen in both views.
    assert counts["fused"]["NO_DEPTH"] < counts["sensor"]["NO_DEPTH"], counts
    assert counts["mesh"]["NO_DEPTH"] < counts["sensor"]["NO_DEPTH"], counts
    assert counts["fused"]["VISIBLE"] > counts["sensor"]["VISIBLE"] * 0.95, counts
    # No mesh: a clear error naming the scene.
    r = common.occgt("pair", *pair, "--depth-source", "mesh", "--out", common.scratch("pair_nomesh"), check=False)
    assert r.returncode == 1 and "needs a mesh" in r.stderr, r.stderr
    r = common.occgt("pair", *pair, "--depth-source", "lidar", "--out", common.scratch("pair_bad"), check=False)
    assert r.returncode == 2 and "--depth-source" in r.stderr and r.stderr.count("\n") == 1, r.stderr


def test_scan_mesh():
    r = common.occgt("scan", ROOT, "--format", "sevenscenes", "--json", "--mesh", MESH, "--mesh-stride", "10")
    doc = json.loads(r.stdout)
    jsonschema.validate(doc, schema("scan.schema.json"))
    m = doc["scenes"][0]["mesh_depth"]
    assert m["mesh"] == MESH and len(m["frames"]) == 5
    assert m["total"]["shares"]["agree"] > 0.75 and m["total"]["mesh_only"] > 0, m["total"]
    # The same record as render.json's sensor: counts summing to pixels, shares beside them.
    for rec in m["frames"] + [m["total"]]:
        classes = ("sensor_only", "mesh_only", "agree", "disagree", "neither")
        assert sum(rec[c] for c in classes) == rec["pixels"], rec
        assert all(abs(rec["shares"][c] - rec[c] / rec["pixels"]) < 1e-12 for c in classes[:4]), rec
    assert m["total"]["pixels"] == sum(f["pixels"] for f in m["frames"]), m
    plain = json.loads(common.occgt("scan", ROOT, "--format", "sevenscenes", "--json").stdout)
    assert "mesh_depth" not in plain["scenes"][0]
    text = common.occgt("scan", ROOT, "--format", "sevenscenes", "--mesh", MESH, "--mesh-stride", "25").stdout
    assert "2 frames vs sensor (within 0.2 m + 0.01 of depth): agree" in text, text


RECIPE = """name: sevenscenes-fused
split: fused
seed: 0
resolution: [320, 240]
dataset:
  format: sevenscenes
  root: {root}
  frame_stride: 2
  depth_source: {source}
  mesh_path: {mesh}
labels: {{preset: default}}
selection: {{max_frame_gap: 6, score_stride: 8, overlap: [0.3, 0.95], quota_per_scene: 4}}
occupancy: {{enabled: false}}
sample: {{image: none, depth: true, labels: true, occupancy: false}}
shards: {{samples_per_shard: 4}}
"""


def test_build_depth_source():
    """`occgt build` with dataset.depth_source fused and the mesh as dataset.mesh_path: fewer
    NO_DEPTH pixels than the same recipe with --depth-source sensor (which is the sensor
    build: the override, checked by the digests of its shards' depth against the sensor
    recipe's)."""
    ws = common.scratch("render_build")

    def no_depth(out):  # (NO_DEPTH pixels of direction 0->1 over the pairs, pairs)
        with open(os.path.join(out, "pairs.jsonl")) as f:
            lines = [json.loads(line) for line in f]
        return sum(p["metrics"]["01"]["counts"]["NO_DEPTH"] for p in lines), len(lines)

    counts = {}
    for source in ("sensor", "fused"):
        path = os.path.join(ws, source + ".yaml")
        with open(path, "w") as f:
            f.write(RECIPE.format(root=os.path.dirname(ROOT) + "/sevenscenes", source=source, mesh=MESH))
        out = os.path.join(ws, "out_" + source)
        summary = json.loads(common.occgt("build", "--json", path, "--out", out).stdout)
        assert summary["complete"] and summary["samples"] > 0, summary
        counts[source] = no_depth(out)
    over = os.path.join(ws, "out_override")
    common.occgt("build", "--json", os.path.join(ws, "fused.yaml"), "--out", over, "--depth-source", "sensor")
    assert no_depth(over) == counts["sensor"], (no_depth(over), counts)
    assert counts["fused"][0] / counts["fused"][1] < counts["sensor"][0] / counts["sensor"][1], counts


def test_bad_render_flags():
    out = common.scratch("render_bad")
    r = common.occgt("render", *ARGS, "--out", out, check=False)
    assert r.returncode == 2 and "--mesh" in r.stderr, r.stderr
    r = common.occgt("render", *ARGS, "--mesh", MESH, "--frames", "999", "--out", out, check=False)
    assert r.returncode == 2 and "--frames" in r.stderr, r.stderr
    bad = os.path.join(out, "bad.ply")
    with open(bad, "w") as f:
        f.write("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nend_header\n")
    r = common.occgt("render", *ARGS, "--mesh", bad, "--out", out, check=False)
    assert r.returncode == 1 and bad in r.stderr and r.stderr.count("\n") == 1, r.stderr


def test_render_bad_sensor_and_nothing_half_written():
    # A sensor depth file that cannot be read: the frame is rendered all the same, its
    # comparison null with the reason (it stopped the render, leaving the earlier frames'
    # files behind).
    root = common.scratch("render_bad_sensor")
    os.makedirs(os.path.join(root, "rgbd-frames"))
    os.symlink(os.path.join(ROOT, "camera-intrinsics.txt"), os.path.join(root, "camera-intrinsics.txt"))
    for fid in ("000150", "000160"):
        for part in ("color.png", "depth.png", "pose.txt"):
            src = os.path.join(ROOT, "rgbd-frames", f"frame-{fid}.{part}")
            dst = os.path.join(root, "rgbd-frames", f"frame-{fid}.{part}")
            if fid == "000160" and part == "depth.png":
                with open(src, "rb") as f, open(dst, "wb") as g:
                    g.write(f.read()[:200])
            else:
                os.symlink(src, dst)
    args = ["--root", root, "--format", "sevenscenes", "--scene", "rgbd-frames", "--mesh", MESH,
            "--frames", "000150,000160"]
    out = os.path.join(root, "out")
    r = common.occgt("render", *args, "--out", out)
    assert "  sensor depth unreadable for frame 000160: " in r.stdout, r.stdout
    with open(os.path.join(out, "render.json")) as f:
        doc = json.load(f)
    jsonschema.validate(doc, schema("render.schema.json"))
    second = doc["frames"][1]
    assert second["sensor"] is None and "truncated PNG" in second["sensor_error"], second
    assert doc["frames"][0]["sensor"] is not None and "sensor_error" not in doc["frames"][0]
    assert os.path.exists(os.path.join(out, "000160_depth.npy"))
    # A frame that fails to be written leaves no file of the run, and an earlier file of the
    # same name as it was.
    out2 = os.path.join(root, "out2")
    os.makedirs(os.path.join(out2, "000160_depth.npy.part"))  # its file cannot be written
    with open(os.path.join(out2, "000150_depth.npy"), "w") as f:
        f.write("an earlier run's file")
    r = common.occgt("render", *args, "--out", out2, check=False)
    assert r.returncode == 1 and r.stderr.count("\n") == 1, (r.returncode, r.stderr)
    left = sorted(n for n in os.listdir(out2) if n != ".render.lock")
    assert left == ["000150_depth.npy", "000160_depth.npy.part"], left
    with open(os.path.join(out2, "000150_depth.npy")) as f:
        assert f.read() == "an earlier run's file"


def test_render_interrupted_and_stale_temporaries():
    # A run removes the temporaries an earlier, killed run left under render's own names
    # (and no other file); Ctrl-C or SIGTERM prints one line, removes this run's temporary
    # files, keeps the earlier run's files and ends by the signal (they stayed, ~14 MB).
    out = common.scratch("render_interrupted")
    stale = ["000160_depth.npy.part", "000170_picture.png.part", "000180_triangles.npy.part.tmp",
             "render.json.tmp"]
    others = ["notes.part", "000160_depth.npy.partial", "my_render.json.tmp"]
    for name in stale + others:
        with open(os.path.join(out, name), "w") as f:
            f.write("x")
    common.occgt("render", *ARGS, "--mesh", MESH, "--frames", "000150", "--out", out)
    left = sorted(n for n in os.listdir(out) if n != ".render.lock")
    assert left == sorted(others + ["000150_depth.npy", "000150_depth.png", "000150_picture.png",
                                    "000150_triangles.npy", "render.json"]), left
    with open(os.path.join(out, "render.json"), "rb") as f:
        earlier = f.read()
    for sig in (signal.SIGINT, signal.SIGTERM):
        p = subprocess.Popen([common.BINARY, "render", *ARGS, "--mesh", MESH,
                              "--out", out], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                             text=True, start_new_session=True)
        deadline = time.time() + 60
        while p.poll() is None and time.time() < deadline and \
                not any(n.endswith(".part") and n not in others for n in os.listdir(out)):
            time.sleep(0.01)
        assert p.poll() is None, "render ended before it could be interrupted"
        time.sleep(0.2)
        os.killpg(p.pid, sig)  # as a terminal's Ctrl-C does (the process group)
        _, err = p.communicate(timeout=60)
        assert p.returncode == -sig, (sig, p.returncode, err)
        lines = [x for x in err.splitlines() if x]
        assert lines == ["occgt: interrupted; the files of this run are removed, earlier ones "
                         "kept; re-run the same command"], (sig, err)
        now = sorted(n for n in os.listdir(out) if n != ".render.lock")
        assert now == left, (sig, now)
        with open(os.path.join(out, "render.json"), "rb") as f:
            assert f.read() == earlier, sig


if __name__ == "__main__":
    test_render_interrupted_and_stale_temporaries()
    test_render()
    test_render_bad_sensor_and_nothing_half_written()
    test_pair_depth_source()
    test_scan_mesh()
    test_build_depth_source()
    test_bad_render_flags()
    print("OK")
