"""A folder of TartanAir trajectories (ROOT/P000, ROOT/P001: the shape of ENV/Easy/) built in
the scratch folder from symlinks to the real sample's files: `occgt scan` lists both
trajectories by folder name, a recipe with `dataset.scenes: [P000]` builds pairs of P000 only,
and `scenes: [P002]` fails with one line naming the scene. One environment's folder
(ENV/{Easy,Hard}/Pxxx) lists its trajectories as Easy/Pxxx and Hard/Pxxx and builds."""
import json
import os
import sys

import cv2
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common  # noqa: E402

FRAMES = 6


def make_root(sample, tmp, name="trajectories", trajectories=(("P000", 0), ("P001", 10))):
    """ROOT/P000 = sample frames 0-5, ROOT/P001 = frames 10-15 renumbered 0-5."""
    root = os.path.join(tmp, name)
    with open(os.path.join(sample, "pose_left.txt")) as f:
        poses = [line for line in f.read().splitlines() if line.strip()]
    for traj, first in trajectories:
        d = os.path.join(root, traj)
        os.makedirs(os.path.join(d, "depth_left"))
        os.makedirs(os.path.join(d, "image_left"))
        for i in range(FRAMES):
            for sub, suffix in (("depth_left", "_left_depth.npy"), ("image_left", "_left.png")):
                os.symlink(os.path.join(sample, sub, f"{first + i:06d}{suffix}"),
                           os.path.join(d, sub, f"{i:06d}{suffix}"))
        with open(os.path.join(d, "pose_left.txt"), "w") as f:
            f.write("\n".join(poses[first:first + FRAMES]) + "\n")
    return root


RECIPE = """name: tartanair-folder
split: tartanair-folder
seed: 0
resolution: [320, 240]
dataset:
  format: tartanair
  root: {root}
  scenes: [{scene}]
  max_depth_m: 100
selection:
  max_frame_gap: 2
  overlap: [0.3, 1.0]
  quota_per_scene: 3
occupancy: {{enabled: false}}
sample: {{image: png, labels: true, occupancy: false}}
"""


def main():
    sample = common.shared("tartanair/hospital_sample")
    tmp = common.scratch("tartanair_folder")
    root = make_root(sample, tmp)

    r = common.occgt("scan", root, "--format", "tartanair", "--json")
    doc = json.loads(r.stdout)
    names = [s["name"] for s in doc["scenes"]]
    assert names == ["P000", "P001"], names
    assert all(s["frames"] == FRAMES and s["usable"] == FRAMES for s in doc["scenes"]), doc["scenes"]

    recipe = os.path.join(tmp, "recipe.yaml")
    with open(recipe, "w") as f:
        f.write(RECIPE.format(root=root, scene="P000"))
    out = os.path.join(tmp, "out")
    common.occgt("build", "--json", recipe, "--out", out)
    with open(os.path.join(out, "summary.json")) as f:
        summary = json.load(f)
    assert summary["complete"] and summary["samples"] > 0, summary
    with open(os.path.join(out, "pairs.jsonl")) as f:
        pairs = [json.loads(line) for line in f]
    assert len(pairs) == summary["samples"], (len(pairs), summary["samples"])
    assert {p["scene"] for p in pairs} == {"P000"}, {p["scene"] for p in pairs}

    with open(recipe, "w") as f:
        f.write(RECIPE.format(root=root, scene="P002"))
    r = common.occgt("build", "--json", recipe, "--out", os.path.join(tmp, "out_missing"), check=False)
    lines = r.stderr.strip().splitlines()
    assert r.returncode != 0 and len(lines) == 1 and "P002" in lines[0], (r.returncode, r.stderr)

    # One environment: ENV/Easy/P000, ENV/Hard/P001.
    env = make_root(sample, tmp, "hospital", (("Easy/P000", 0), ("Hard/P001", 10)))
    doc = json.loads(common.occgt("scan", env, "--format", "tartanair", "--json").stdout)
    env_names = [s["name"] for s in doc["scenes"]]
    assert env_names == ["Easy/P000", "Hard/P001"], env_names
    assert all(s["usable"] == FRAMES for s in doc["scenes"]), doc["scenes"]
    with open(recipe, "w") as f:
        f.write(RECIPE.format(root=env, scene="Hard/P001"))
    out_env = os.path.join(tmp, "out_env")
    common.occgt("build", "--json", recipe, "--out", out_env)
    with open(os.path.join(out_env, "pairs.jsonl")) as f:
        env_pairs = [json.loads(line) for line in f]
    assert env_pairs and {p["scene"] for p in env_pairs} == {"Hard/P001"}, env_pairs[:1]
    # The same frames give the same metrics whichever layout holds them (which pairs the
    # quota keeps is seeded by the scene name, so compare the pairs both kept).
    def strip(p):
        return {k: v for k, v in p.items() if k not in ("scene", "key", "shard", "index")}
    ref = os.path.join(tmp, "out_ref")
    with open(recipe, "w") as f:
        f.write(RECIPE.format(root=root, scene="P001"))
    common.occgt("build", "--json", recipe, "--out", ref)
    with open(os.path.join(ref, "pairs.jsonl")) as f:
        ref_pairs = [json.loads(line) for line in f]
    by_frames = {(p["frame0"]["id"], p["frame1"]["id"]): strip(p) for p in ref_pairs}
    common_pairs = [p for p in env_pairs if (p["frame0"]["id"], p["frame1"]["id"]) in by_frames]
    assert common_pairs, (env_pairs, ref_pairs)
    for p in common_pairs:
        assert strip(p) == by_frames[(p["frame0"]["id"], p["frame1"]["id"])], p["key"]
    # Colour images that cannot be stored (not an image; another size) are that frame's
    # problem: skipped, counted and named (scan.color_error), and the build completes. It
    # used to fail as a whole when the first sample with such a frame was written.
    bad = make_root(sample, tmp, "bad_colour", (("P000", 0),))
    images = os.path.join(bad, "P000", "image_left")
    os.unlink(os.path.join(images, "000001_left.png"))
    with open(os.path.join(images, "000001_left.png"), "wb") as f:
        f.write(b"not an image")
    os.unlink(os.path.join(images, "000003_left.png"))
    cv2.imwrite(os.path.join(images, "000003_left.png"), np.zeros((480, 640, 3), np.uint8)[::2, ::2])
    with open(recipe, "w") as f:
        f.write(RECIPE.format(root=bad, scene="P000"))
    out_bad = os.path.join(tmp, "out_bad_colour")
    r = common.occgt("build", recipe, "--out", out_bad)
    with open(os.path.join(out_bad, "summary.json")) as f:
        s = json.load(f)
    assert s["complete"] and s["drops"]["scan.color_error"] == 2, s["drops"]
    first = s["drop_examples"]["scan.color_error"]
    assert first.startswith("P000/000001: ") and "000001_left.png" in first, first
    assert "  first scan.color_error: P000/000001: " in r.stdout, r.stdout
    with open(os.path.join(out_bad, "pairs.jsonl")) as f:
        used = {p[k]["id"] for p in map(json.loads, f) for k in ("frame0", "frame1")}
    assert used and not used & {"000001", "000003"}, used
    common.occgt("validate", out_bad)

    # The same damage found by occgt tuples --shards in a view of a stored graph (the
    # TartanAir reader does not read colour headers): named as the colour file's problem,
    # before anything is written (it was reported as too few valid depth pixels).
    tup = make_root(sample, tmp, "tuples_colour", (("P000", 0),))
    recipe_t = os.path.join(tmp, "tuples.yaml")
    with open(recipe_t, "w") as f:
        f.write(RECIPE.format(root=tup, scene="P000").replace(
            "selection:\n", "selection:\n  views: 3\n  tuples: {edge_threshold: 0.1, "
            "quota_per_scene: 4}\n"))
    out_t = os.path.join(tmp, "out_tuples")
    r = common.occgt("covis", recipe_t, "--out", out_t)
    assert r.stdout.startswith("1 scene written, 0 already complete; "), r.stdout  # not "1 scenes"
    # Graphs of another recipe in the folder (other options: another resolution; no scene of
    # these names) are refused before anything is written; they and this recipe's used to
    # mix. Graphs of the same options for other scenes (a recipe's scene subset) are not.
    other = os.path.join(tmp, "other.yaml")
    with open(other, "w") as f:
        f.write(RECIPE.format(root=make_root(sample, tmp, "tuples_other", (("P007", 0),)),
                              scene="P007").replace("[320, 240]", "[160, 120]"))
    r = common.occgt("covis", other, "--out", out_t, check=False)
    assert r.returncode == 1 and f"{out_t}/covisibility/P000.npz: written under another recipe " \
        "(options digest " in r.stderr and "one recipe per --out" in r.stderr, r.stderr
    assert sorted(os.listdir(os.path.join(out_t, "covisibility"))) == ["P000.npz"]
    subset = os.path.join(tmp, "subset.yaml")
    with open(subset, "w") as f:
        f.write(RECIPE.format(root=make_root(sample, tmp, "tuples_subset", (("P008", 0),)),
                              scene="P008").replace(
            "selection:\n", "selection:\n  views: 3\n  tuples: {edge_threshold: 0.1, "
            "quota_per_scene: 4}\n"))
    common.occgt("covis", subset, "--out", out_t)
    os.remove(os.path.join(out_t, "covisibility", "P008.npz"))
    r = common.occgt("tuples", recipe_t, "--out", out_t)
    with open(os.path.join(out_t, "tuples.jsonl")) as f:
        count = sum(1 for _ in f)
    expected = f"{count} tuple{'' if count == 1 else 's'} from 1 scene written to {out_t}/tuples.jsonl"
    assert r.stdout.startswith(expected + "\n"), r.stdout
    with open(os.path.join(out_t, "tuples.jsonl")) as f:
        view = json.loads(f.readline())["frame_ids"][0]
    png = os.path.join(tup, "P000", "image_left", f"{view}_left.png")
    os.unlink(png)
    with open(png, "wb") as f:
        f.write(b"not an image")
    r = common.occgt("tuples", recipe_t, "--out", out_t, "--shards", check=False)
    assert r.returncode == 1 and f"'{view}' has a file that cannot be used (" in r.stderr and \
        "unsupported image format" in r.stderr, r.stderr
    assert not os.path.exists(os.path.join(out_t, "views")), "shards written before the check"

    print(f"tartanair_folder: scan lists {names} and {env_names}; scenes [P000] built {len(pairs)} pairs")


if __name__ == "__main__":
    main()
