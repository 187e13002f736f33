"""The LoFTR export's intrinsics.npz holds K at 640x480, the size LoFTR's ScanNet loader
resizes images to and uses intrinsics.npz with unchanged (docs/READING_SHARDS.md), whatever
the recipe's working resolution.

- The demo (320x240 shards): K of each scene is the sample json's K0 at 320x240 scaled to
  640x480 with the pixel-centre rule (fx, fy doubled, c' = 2 (c + 0.5) - 0.5).
- The TartanAir sample built at 320x240 with a train export: K is the dataset's own K at
  its native 640x480 (fx = fy = 320, cx = 320, cy = 240, as `occgt scan` reports for the
  real sample), while the shards' K0 is at 320x240.
"""
import json
import os
import sys
import tarfile

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
import common  # noqa: E402


def fail(msg):
    sys.exit(f"FAIL: {msg}")


def sample_jsons(build):
    """{scene: the first sample json of that scene} over the build's shards."""
    out = {}
    with open(os.path.join(build, "pairs.jsonl")) as f:
        lines = [json.loads(l) for l in f if l.strip()]
    for line in lines:
        if line["scene"] in out:
            continue
        with tarfile.open(os.path.join(build, line["shard"])) as tf:
            out[line["scene"]] = json.load(tf.extractfile(line["key"] + ".json"))
    return out


def to_640x480(k, width, height):
    sx, sy = 640 / width, 480 / height
    return np.array([[sx * k[0][0], 0, sx * (k[0][2] + 0.5) - 0.5],
                     [0, sy * k[1][1], sy * (k[1][2] + 0.5) - 0.5], [0, 0, 1]])


def main():
    tmp = common.scratch("loftr_intrinsics")
    demo = os.path.join(tmp, "demo")
    common.occgt("build", "--json", os.path.join(common.SOURCE, "recipes", "demo.yaml"), "--out", demo)
    intr = np.load(os.path.join(demo, "loftr", "intrinsics.npz"))
    samples = sample_jsons(demo)
    # Each scene's K under its name and, for non-ScanNet names, under the folder LoFTR
    # looks up ("scene%04d_00" of the scene's place in scenes.txt).
    scenes_txt = open(os.path.join(demo, "loftr", "scenes.txt")).read().split()
    aliases = {f"scene{i:04d}_00": s for i, s in enumerate(scenes_txt)}
    if sorted(intr.files) != sorted(list(samples) + list(aliases)):
        fail(f"demo: intrinsics.npz keys {intr.files}, samples of {sorted(samples)} + {aliases}")
    for alias, scene in aliases.items():
        if not np.array_equal(intr[alias], intr[scene]):
            fail(f"demo: intrinsics.npz[{alias}] is not intrinsics.npz[{scene}]")
    for scene, meta in samples.items():
        if meta["resolution"] != [320, 240]:
            fail(f"demo: resolution {meta['resolution']} (the test needs 320x240 shards)")
        want = to_640x480(meta["K0"], 320, 240)
        if intr[scene].dtype != np.float64 or not np.allclose(intr[scene], want, rtol=0,
                                                              atol=1e-9):
            fail(f"demo {scene}: intrinsics.npz K {intr[scene].tolist()}, want {want.tolist()}"
                 f" (the shard's K0 at 320x240 is {meta['K0']})")

    # TartanAir at 320x240, train export: the dataset's native 640x480 K.
    text = open(os.path.join(common.SOURCE, "recipes", "tartanair-sample.yaml")).read()
    if "resolution: [640, 480]\n" not in text:
        fail("recipes/tartanair-sample.yaml changed: update this test")
    text = "".join(l for l in text.splitlines(True) if not l.startswith("loftr_export:"))
    root = common.shared("tartanair/hospital_sample")
    text = text.replace("resolution: [640, 480]\n", "resolution: [320, 240]\n")
    text = text.replace("${OCCGT_SHARED_DATA:-../../shared/data}/tartanair/hospital_sample", root)
    recipe = os.path.join(tmp, "tartanair-320.yaml")
    with open(recipe, "w") as f:
        f.write(text + "loftr_export: {kind: train}\n")
    build = os.path.join(tmp, "tartanair")
    common.occgt("build", "--json", recipe, "--out", build)
    intr = np.load(os.path.join(build, "loftr", "intrinsics.npz"))
    samples = sample_jsons(build)
    if sorted(intr.files) != sorted(list(samples) + ["scene0000_00"]) or len(samples) != 1:
        fail(f"tartanair: intrinsics.npz keys {intr.files} / samples of {sorted(samples)}")
    k = intr[next(iter(samples))]
    if not np.array_equal(k, [[320, 0, 320], [0, 320, 240], [0, 0, 1]]):
        fail(f"tartanair at 320x240: intrinsics.npz K {k.tolist()}, want TartanAir's 640x480 K")
    k0 = np.array(next(iter(samples.values()))["K0"])
    if not np.allclose(k0, [[160, 0, 159.75], [0, 160, 119.75], [0, 0, 1]], atol=1e-12):
        fail(f"tartanair at 320x240: the shard's K0 {k0.tolist()} is not at 320x240")
    print("loftr intrinsics: ok")


if __name__ == "__main__":
    main()
