"""recipes/scannet-test-1500.yaml pointed (--root) at a synthetic ScanNet-layout fixture
holding exactly the scenes and frames that LoFTR's test.npz names (80x60 depth PNGs of a
plane, small known motions, intrinsic_depth.txt) reproduces the 1500 pairs: the select
stage of the shipped recipe lists them scene by scene in file order, and a full build of
the same recipe at 80x60 exports a test.npz whose names equal LoFTR's and whose rel_pose
is inverse(pose1) @ pose0 of the fixture. Under a sanitizer the full build runs on the
pairs of the first 10 scenes (150 pairs); the select stage still lists all 1500."""
import json
import os
import sys

import numpy as np
import yaml
from PIL import Image

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common  # noqa: E402
from build_demo_test import read_shard, check_sample, validate  # noqa: E402

W, H = 80, 60
FX = 72.0


def pose_of(frame):
    """world_from_cam of a frame: a small translation and yaw that depend on the number."""
    t = frame * 1e-3
    yaw = frame * 2e-4
    c, s = np.cos(yaw), np.sin(yaw)
    m = np.eye(4)
    m[:3, :3] = [[c, 0, s], [0, 1, 0], [-s, 0, c]]
    m[:3, 3] = [t, 0.5 * t, 0.2 * t]
    return m


def make_fixture(root, names):
    scenes = {}
    for s, sub, f0, f1 in names:
        scenes.setdefault(f"scene{s:04d}_{sub:02d}", set()).update((int(f0), int(f1)))
    # A plane at 2.5 m with a raised box in the middle (0.8 m closer): some occlusion.
    depth = np.full((H, W), 2500, np.uint16)
    depth[20:40, 30:50] = 1700
    depth[0:3, 0:5] = 0  # a hole of missing depth
    k = np.array([[FX, 0, (W - 1) / 2, 0], [0, FX, (H - 1) / 2, 0], [0, 0, 1, 0], [0, 0, 0, 1]])
    # Colour as ScanNet's export has it (the shipped recipe stores images).
    colour = Image.fromarray(np.dstack([(depth // 10).astype(np.uint8)] * 3))
    for scene, frames in scenes.items():
        for sub in ("color", "depth", "pose", "intrinsic"):
            os.makedirs(os.path.join(root, scene, sub), exist_ok=True)
        np.savetxt(os.path.join(root, scene, "intrinsic", "intrinsic_depth.txt"), k, fmt="%f")
        for f in frames:
            Image.fromarray(depth).save(os.path.join(root, scene, "depth", f"{f}.png"))
            colour.save(os.path.join(root, scene, "color", f"{f}.jpg"))
            np.savetxt(os.path.join(root, scene, "pose", f"{f}.txt"), pose_of(f), fmt="%.9f")
    return scenes


def main():
    npz_path = common.shared("loftr_scannet_test_1500/test.npz")
    loftr = np.load(npz_path)
    names = loftr["name"].astype(np.int64)
    assert names.shape == (1500, 4)
    root = common.scratch("build_test1500")
    data = os.path.join(root, "scans_test")
    scenes = make_fixture(data, names)
    assert len(scenes) == 100
    env = dict(os.environ, OCCGT_SHARED_DATA=common.SHARED)
    # Expected order: scenes sorted by name, pairs in file order within a scene.
    order = sorted(range(len(names)), key=lambda i: (f"scene{names[i][0]:04d}_{names[i][1]:02d}", i))
    expected = [tuple(int(x) for x in names[i]) for i in order]

    # 1. The shipped recipe, select stage: the 1500 pairs.
    recipe = os.path.join(common.SOURCE, "recipes", "scannet-test-1500.yaml")
    out = os.path.join(root, "select")
    r = common.occgt("build", "--json", recipe, "--out", out, "--root", data, "--stage", "select", env=env)
    summary = json.loads(r.stdout)
    assert summary["counts"]["selected"] == 1500 and summary["scenes"] == 100, summary
    assert summary["drops"] == {}, summary["drops"]
    got = []
    for scene in sorted(scenes):
        with open(os.path.join(out, "selection", scene + ".jsonl")) as f:
            for line in f:
                p = json.loads(line)
                got.append((int(scene[5:9]), int(scene[10:12]), p["frame0"]["number"], p["frame1"]["number"]))
    assert got == expected

    # 1b. A depth map that cannot be decoded drops the pairs that use it at scoring (the
    # import has no scan), counted and named: the first error in summary.json and the text.
    # It is the scene's first depth file, which the reader no longer needs for the size.
    s0, sub0, _, _ = expected[0]
    broken = common.scratch("build_test1500_broken")
    scene0 = f"scene{s0:04d}_{sub0:02d}"
    f0 = min(scenes[scene0])
    os.makedirs(os.path.join(broken, scene0))
    for sub in ("color", "depth", "pose", "intrinsic"):
        os.symlink(os.path.join(data, scene0, sub), os.path.join(broken, scene0, sub))
    os.unlink(os.path.join(broken, scene0, "depth"))
    os.makedirs(os.path.join(broken, scene0, "depth"))
    for name in os.listdir(os.path.join(data, scene0, "depth")):
        os.symlink(os.path.join(data, scene0, "depth", name), os.path.join(broken, scene0, "depth", name))
    os.unlink(os.path.join(broken, scene0, "depth", f"{f0}.png"))
    with open(os.path.join(broken, scene0, "depth", f"{f0}.png"), "wb") as f:
        f.write(b"not a PNG")
    one = [n for n in names if f"scene{n[0]:04d}_{n[1]:02d}" == scene0]
    uses = sum(1 for n in one if f0 in (n[2], n[3]))
    one_npz = os.path.join(broken, "one-scene.npz")
    np.savez(one_npz, **{k: loftr[k][[i for i in range(len(names)) if tuple(names[i]) in
                                      {tuple(n) for n in one}]] for k in loftr.files})
    with open(recipe) as f:
        doc = yaml.safe_load(f)
    doc["selection"]["import_pairs"]["path"] = one_npz
    one_recipe = os.path.join(broken, "one-scene.yaml")
    with open(one_recipe, "w") as f:
        yaml.safe_dump(doc, f)
    r = common.occgt("build", one_recipe, "--out", os.path.join(broken, "out"), "--root", broken,
                     "--stage", "select", env=env)
    s = json.loads(common.occgt("build", "--json", one_recipe, "--out", os.path.join(broken, "out2"),
                                "--root", broken, "--stage", "select", env=env).stdout)
    assert uses > 0 and s["drops"] == {"score.read_error": uses}, (uses, s["drops"])
    assert s["counts"]["selected"] == len(one) - uses, s["counts"]
    example = s["drop_examples"]["score.read_error"]
    assert example.startswith(f"{scene0}/{f0}: ") and f"{f0}.png" in example, example
    assert f"  first score.read_error: {example}" in r.stdout, r.stdout
    validate(s, "summary.schema.json")

    # 1c. A row given twice and a frame paired with itself: skipped and counted (the repeat
    # stopped the build with "two pairs map to the same key after sanitising"); the reversed
    # pair is another pair and stays.
    s0, sub0, a0, b0 = expected[0]
    rows = [i for i in range(len(names)) if f"scene{names[i][0]:04d}_{names[i][1]:02d}" == scene0]
    extra = np.array([[s0, sub0, a0, b0], [s0, sub0, a0, a0], [s0, sub0, b0, a0]], np.int64)
    dup_npz = os.path.join(broken, "repeats.npz")
    np.savez(dup_npz, name=np.concatenate([names[rows], extra]))
    doc["selection"]["import_pairs"]["path"] = dup_npz
    dup_recipe = os.path.join(broken, "repeats.yaml")
    with open(dup_recipe, "w") as f:
        yaml.safe_dump(doc, f)
    s = json.loads(common.occgt("build", "--json", dup_recipe, "--out", os.path.join(broken, "out3"),
                                "--root", data, "--stage", "select", env=env).stdout)
    assert s["drops"] == {"import.duplicate": 1, "import.same_frame": 1}, s["drops"]
    assert s["counts"]["selected"] == len(rows) + 1, s["counts"]
    validate(s, "summary.schema.json")

    # 2. The same recipe at 80x60 without images/occupancy: a full build and the export.
    # Under a sanitizer (common.SANITIZER) on the pairs of the first 10 scenes only (150 of
    # the 1500, a test.npz of those rows): the same code on a tenth of the work.
    import_path = npz_path
    if common.SANITIZER:
        keep = set(sorted(scenes)[:10])
        rows = [i for i in range(len(names)) if f"scene{names[i][0]:04d}_{names[i][1]:02d}" in keep]
        import_path = os.path.join(root, "test-10-scenes.npz")
        np.savez(import_path, **{k: loftr[k][rows] for k in loftr.files})
        expected = [p for p in expected if f"scene{p[0]:04d}_{p[1]:02d}" in keep]
        scenes = {k: v for k, v in scenes.items() if k in keep}
    with open(recipe) as f:
        doc = yaml.safe_load(f)
    doc["resolution"] = [W, H]
    doc["patches"]["stride"] = 4
    doc["occupancy"]["enabled"] = False
    doc["sample"]["image"] = "none"
    doc["selection"]["import_pairs"]["path"] = import_path
    small = os.path.join(root, "test1500-small.yaml")
    with open(small, "w") as f:
        yaml.safe_dump(doc, f)
    out = os.path.join(root, "full")
    common.occgt("build", "--json", small, "--out", out, "--root", data, env=env)
    t = np.load(os.path.join(out, "loftr", "test.npz"))
    assert np.array_equal(t["name"].astype(np.int64), np.array(expected)), "names differ"
    for row, (s, sub, f0, f1) in zip(t["rel_pose"], expected):
        want = (np.linalg.inv(pose_of(f1)) @ pose_of(f0))[:3]
        assert np.allclose(row.reshape(3, 4), want, atol=1e-5)
    with open(os.path.join(out, "loftr", "statistics.json")) as f:
        stats = json.load(f)
    assert len(stats) == len(scenes) and all(v == 15 for v in stats.values())
    intr = np.load(os.path.join(out, "loftr", "intrinsics.npz"))
    assert len(intr.files) == len(scenes)
    k = intr["scene0707_00"]
    # K at 640x480, the size LoFTR resizes to (docs/READING_SHARDS.md), not at the 80x60 of
    # the shards: the fixture's K scaled by 8 with the pixel-centre rule.
    s = 640 / W
    assert np.allclose(k, [[s * FX, 0, s * W / 2 - 0.5], [0, s * FX, s * H / 2 - 0.5], [0, 0, 1]])
    # The shipped recipe writes the LoFTR tree too (loftr_export.tree): exactly the frames
    # test.npz names, one folder per scene.
    tree = json.load(open(os.path.join(out, "loftr", "tree.json")))
    validate(tree, "loftr_tree.schema.json")
    assert tree["frames"] == sum(len(f) for f in scenes.values()), tree
    assert sorted(os.listdir(os.path.join(out, "loftr", "data"))) == sorted(scenes)
    for sub in ("color", "depth", "pose"):
        got = os.listdir(os.path.join(out, "loftr", "data", "scene0707_00", sub))
        assert len(got) == len(scenes["scene0707_00"]), (sub, got)
    # Every sample is there, with depth for Occ2Net's test step.
    with open(os.path.join(out, "index.json")) as f:
        index = json.load(f)
    n = 0
    for shard in index["shardlist"]:
        for key, fields in read_shard(os.path.join(out, shard["url"])).items():
            meta = json.loads(fields["json"])
            validate(meta, "sample.schema.json")
            assert "depth0.npy" in fields and "image0.png" not in fields and "occ0.npy" not in fields
            assert meta["metrics"]["01"]["counts"]["OCCLUDED"] >= 0
            n += 1
    assert n == len(expected)
    print("build_test1500: 1 passed, 0 failed")


if __name__ == "__main__":
    main()
