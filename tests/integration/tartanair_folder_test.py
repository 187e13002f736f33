"""A folder of TartanAir trajectories (ROOT/P000, ROOT/P001: the shape of ENV/Easy/) built in
the scratch folder from symlinks to the real sample's files: `occgt scan` lists both
trajectories by folder name, a recipe with `dataset.scenes: [P000]` builds pairs of P000 only,
and `scenes: [P002]` fails with one line naming the scene."""
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common  # noqa: E402

FRAMES = 6


def make_root(sample, tmp):
    """ROOT/P000 = sample frames 0-5, ROOT/P001 = frames 10-15 renumbered 0-5."""
    root = os.path.join(tmp, "trajectories")
    with open(os.path.join(sample, "pose_left.txt")) as f:
        poses = [line for line in f.read().splitlines() if line.strip()]
    for traj, first in (("P000", 0), ("P001", 10)):
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
    print(f"tartanair_folder: scan lists {names}; scenes [P000] built {len(pairs)} pairs")


if __name__ == "__main__":
    main()
