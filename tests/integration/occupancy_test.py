"""occgt occupancy on the real TartanAir sample, read the way a trainer would: the packed
words are unpacked with exactly the NumPy snippet of docs/OCCUPANCY.md, compared with
--dense, and occupancy.json is validated against schemas/occupancy.schema.json. A window or
scene scope lists its unusable frames in fusion.skipped_frames (they were left out without
a word), and a build of such a scope still builds."""
import json
import os
import re
import sys

import jsonschema
import numpy as np

import common


def doc_snippet():
    text = open(os.path.join(common.SOURCE, "docs", "OCCUPANCY.md")).read()
    m = re.search(r"<!-- unpack-snippet -->\s*```python\n(.*?)```", text, re.S)
    assert m, "docs/OCCUPANCY.md lost its unpack snippet"
    scope = {}
    exec(m.group(1), scope)
    return scope["unpack_occupancy"]


def main():
    unpack = doc_snippet()
    root = common.shared("tartanair/hospital_sample")
    schema = json.load(open(os.path.join(common.SOURCE, "schemas", "occupancy.schema.json")))
    out = common.scratch("occupancy_tartanair")
    common.occgt("occupancy", "--root", root, "--format", "tartanair", "--scene", "",
                 "--frames", "000000,000020", "--out", out, "--dense",
                 "--save-octree", os.path.join(out, "map.bt"))
    meta = json.load(open(os.path.join(out, "occupancy.json")))
    jsonschema.validate(meta, schema)
    assert meta["fusion"]["downsample"] is False, "downsampling is off by default"
    w, h = meta["grid"]
    assert (w, h) == (320, 240), meta["grid"]
    d = meta["bins"]["num_bins"]
    assert len(meta["bins"]["edges_m"]) == d + 1
    for cam in "01":
        occ = np.load(os.path.join(out, f"occ{cam}.npy"))
        known = np.load(os.path.join(out, f"known{cam}.npy"))
        dense = np.load(os.path.join(out, f"occ{cam}_dense.npy"))
        assert occ.dtype == np.dtype("<u8") and occ.shape == (h, w), (occ.dtype, occ.shape)
        assert known.dtype == np.dtype("<u8") and known.shape == (h, w)
        assert dense.dtype == np.uint8 and dense.shape == (d, h, w), (dense.dtype, dense.shape)
        assert np.all(occ & ~known == 0), "occupied bits outside known bits"
        unpacked = unpack(occ, known, d)
        assert unpacked.dtype == np.uint8 and unpacked.shape == (d, h, w)
        assert np.array_equal(unpacked, dense), "snippet disagrees with --dense"
        counts = meta["counts" + cam]
        assert counts["occupied"] == int((dense == 1).sum())
        assert counts["free"] == int((dense == 0).sum())
        assert counts["unknown"] == int((dense == 255).sum())
        assert 0 < counts["occupied"] and 0 < counts["free"], counts
    # Every pixel of the two frames is counted: invalid, out of the key range, or inserted.
    st = meta["fusion"]["stats"]
    assert st["frames"] == 2 and st["pixels"] == 2 * 640 * 480, st
    assert st["invalid_pixels"] + st["out_of_key_range"] + st["inserted_points"] == st["pixels"], st
    assert st["inserted_points"] > 0 and st["leaf_nodes"] > 0, st
    with open(os.path.join(out, "map.bt"), "rb") as f:
        assert f.readline().startswith(b"# Octomap OcTree binary file")

    # Deterministic: a second run writes identical bytes.
    out2 = common.scratch("occupancy_tartanair_again")
    common.occgt("occupancy", "--root", root, "--format", "tartanair", "--scene", "",
                 "--frames", "000000,000020", "--out", out2, "--dense")
    for name in ["occ0.npy", "known0.npy", "occ1.npy", "known1.npy", "occ0_dense.npy",
                 "occ1_dense.npy"]:
        assert open(os.path.join(out, name), "rb").read() == \
            open(os.path.join(out2, name), "rb").read(), name
    # A re-run into that folder without --dense leaves no stale dense volume beside its
    # words (they stayed, of the earlier bins).
    common.occgt("occupancy", "--root", root, "--format", "tartanair", "--scene", "",
                 "--frames", "000000,000020", "--out", out2, "--bins", "8")
    assert sorted(os.listdir(out2)) == ["known0.npy", "known1.npy", "occ0.npy", "occ1.npy",
                                        "occupancy.json"], sorted(os.listdir(out2))

    # two_point and a window scope with other bin options also validate.
    out3 = common.scratch("occupancy_two_point")
    common.occgt("occupancy", "--root", root, "--format", "tartanair", "--scene", "",
                 "--frames", "000000,000020", "--out", out3, "--mode", "two_point",
                 "--bins", "32", "--spacing", "inverse")
    meta3 = json.load(open(os.path.join(out3, "occupancy.json")))
    jsonschema.validate(meta3, schema)
    assert meta3["fusion"]["stats"] is None, "two_point fuses nothing"
    occ = np.load(os.path.join(out3, "occ0.npy"))
    assert np.all(occ >> np.uint64(32) == 0), "bits above num_bins set"
    out4 = common.scratch("occupancy_window")
    common.occgt("occupancy", "--root", root, "--format", "tartanair", "--scene", "",
                 "--frames", "000000,000020", "--out", out4, "--scope", "window:2",
                 "--traversal", "center", "--resolution", "320x240", "--downsample")
    meta4 = json.load(open(os.path.join(out4, "occupancy.json")))
    jsonschema.validate(meta4, schema)
    assert meta4["fusion"]["downsample"] is True, "--downsample turns it on"
    assert meta4["grid"] == [160, 120]
    assert len(meta4["fusion"]["fused_frames"]) == 8, meta4["fusion"]["fused_frames"]

    # Usage errors (docs/CLI.md): one `occgt: error: --flag` line, exit 2, nothing written.
    out5 = common.scratch("occupancy_bad")
    r = common.occgt("occupancy", "--root", root, "--format", "tartanair", "--scene", "",
                     "--frames", "000000,000020", "--out", out5, "--scope", "window:0",
                     check=False)
    assert r.returncode == 2 and r.stderr.startswith("occgt: error: --scope: "), r.stderr
    assert r.stderr.count("\n") == 1, r.stderr
    assert os.listdir(out5) == []
    # A voxel size whose 16-bit key range (+-32766 voxels around the origin) cannot hold the
    # 10 m ray range would drop every point: refused before fusing, naming the flag and the
    # smallest voxel size that works.
    r = common.occgt("occupancy", "--root", root, "--format", "tartanair", "--scene", "",
                     "--frames", "000000,000020", "--out", out5, "--voxel-m", "1e-6",
                     check=False)
    assert r.returncode == 2, (r.returncode, r.stderr)
    assert re.fullmatch(r"occgt: error: --voxel-m: 1e-06 m holds \+-0\.0328 m around the world "
                        r"origin .* with max_range_m 10 needs \+-.* m: use voxel_m >= \S+\n",
                        r.stderr), r.stderr
    assert os.listdir(out5) == []
    # A --min-depth-m above the dataset's max depth: named after that flag, exit 2 (it was
    # "occupancy options: ...", exit 1, naming no flag).
    for cmd in ("occupancy", "pair"):
        r = common.occgt(cmd, "--root", root, "--format", "tartanair", "--scene", "",
                         "--frames", "000000,000020", "--out", out5, "--min-depth-m", "5000",
                         check=False)
        assert r.returncode == 2 and r.stderr.startswith(
            "occgt: error: --min-depth-m: max_depth_m must be > min_depth_m (5000)"), r.stderr
        assert os.listdir(out5) == []
    # The fusion's flags with --mode two_point, which fuses nothing: refused (they were
    # recorded in occupancy.json and not applied).
    for flag in (["--scope", "window:1"], ["--voxel-m", "0.1"], ["--max-range-m", "5"],
                 ["--traversal", "center"], ["--downsample"], ["--remove-outliers"],
                 ["--remove-outliers", "--outlier-k", "5"]):
        r = common.occgt("occupancy", "--root", root, "--format", "tartanair", "--scene", "",
                         "--frames", "000000,000020", "--out", out5, "--mode", "two_point",
                         *flag, check=False)
        assert r.returncode == 2, (flag, r.returncode, r.stderr)
        assert r.stderr == (f"occgt: error: {flag[0]}: used by --mode octomap only (two_point "
                            "fuses nothing)\n"), r.stderr
        assert os.listdir(out5) == []
    # The outlier removal's parameters: recorded when it is on, refused without it.
    out6 = common.scratch("occupancy_outliers")
    common.occgt("occupancy", "--root", root, "--format", "tartanair", "--scene", "",
                 "--frames", "000000,000020", "--out", out6, "--resolution", "320x240",
                 "--remove-outliers", "--outlier-k", "6", "--outlier-stddev", "0.5")
    meta6 = json.load(open(os.path.join(out6, "occupancy.json")))
    jsonschema.validate(meta6, schema)
    fusion = meta6["fusion"]
    assert (fusion["remove_outliers"], fusion["outlier_k"], fusion["outlier_stddev"]) == (
        True, 6, 0.5), fusion
    assert fusion["stats"]["outliers_removed"] > 0, fusion["stats"]
    for flags, message in (
            (["--outlier-k", "6"], "--outlier-k: used with --remove-outliers (or a --recipe's "
                                   "occupancy.remove_outliers: true) only"),
            (["--outlier-stddev", "1"], "--outlier-stddev: used with --remove-outliers"),
            (["--remove-outliers", "--outlier-k", "0"], "--outlier-k: outlier_k must be >= 1"),
            (["--remove-outliers", "--outlier-stddev", "-1"],
             "--outlier-stddev: outlier_stddev must be > 0")):
        r = common.occgt("occupancy", "--root", root, "--format", "tartanair", "--scene", "",
                         "--frames", "000000,000020", "--out", out5, *flags, check=False)
        assert r.returncode == 2 and r.stderr.startswith("occgt: error: " + message), (
            flags, r.returncode, r.stderr)
        assert os.listdir(out5) == []
    scope_unusable_frames(schema)
    print("occupancy integration: ok")


def scope_unusable_frames(schema):
    """Frame 000003 of a synthetic scene gets a non-rigid pose (the reader marks it unusable):
    a window:1 scope around 000002,000004 and a scene:1 scope leave it out of the fusion and
    say so in fusion.skipped_frames, with the reader's reason; `occgt build` of a window scope
    still builds every pair (the frame is counted under scan.* there)."""
    tmp = common.scratch("occupancy_scope_unusable")
    data = os.path.join(tmp, "data")
    common.occgt("synth", "--out", data, "--scenes", "1", "--frames", "8", "--resolution",
                 "64x48")
    manifest = os.path.join(data, "synth_000", "scene.json")
    doc = json.load(open(manifest))
    doc["frames"][3]["world_from_cam"] = [[2, 0, 0, 0], [0, 2, 0, 0], [0, 0, 2, 0], [0, 0, 0, 1]]
    json.dump(doc, open(manifest, "w"))
    for scope, fused in (("window:1", ["000001", "000002", "000004", "000005"]),
                         ("scene:1", ["000000", "000001", "000002", "000004", "000005", "000006",
                                      "000007"])):
        out = os.path.join(tmp, scope.replace(":", "_"))
        r = common.occgt("occupancy", "--root", data, "--format", "generic", "--scene",
                         "synth_000", "--frames", "000002,000004", "--scope", scope,
                         "--resolution", "64x48", "--out", out)
        meta = json.load(open(os.path.join(out, "occupancy.json")))
        jsonschema.validate(meta, schema)
        assert meta["fusion"]["fused_frames"] == fused, (scope, meta["fusion"]["fused_frames"])
        skipped = meta["fusion"]["skipped_frames"]
        assert [s["frame"] for s in skipped] == ["000003"], (scope, skipped)
        assert skipped[0]["reason"].startswith(
            "unusable: pose: rotation is not orthonormal"), (scope, skipped)
        assert "scene.json: frames[3].world_from_cam" in skipped[0]["reason"], (scope, skipped)
        assert "skipped 1 frame(s) of the scope" in r.stdout, (scope, r.stdout)
    recipe = os.path.join(tmp, "recipe.yaml")
    with open(recipe, "w") as f:
        f.write(f"""name: scope-unusable
split: scope
resolution: [64, 48]
dataset:
  format: generic
  root: {data}
  min_valid_depth_fraction: 0.1
selection:
  max_frame_gap: 2
  score_stride: 4
  overlap: [0.0, 1.0]
  pruning: {{frustum: false, max_distance_m: 100, max_view_angle_deg: 180}}
occupancy: {{enabled: true, scope: window, window: 1}}
sample: {{image: none, depth: false, labels: true, occupancy: true}}
shards: {{samples_per_shard: 4}}
""")
    build = os.path.join(tmp, "build")
    summary = json.loads(common.occgt("build", "--json", recipe, "--out", build).stdout)
    assert summary["drops"] == {"scan.unusable": 1}, summary["drops"]
    with open(os.path.join(build, "pairs.jsonl")) as f:
        keys = [json.loads(line)["key"] for line in f]
    assert "synth_000/000002_000004" in keys, keys  # its window holds 000003
    assert summary["samples"] == len(keys), (summary["samples"], keys)


if __name__ == "__main__":
    sys.exit(main())
