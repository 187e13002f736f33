#!/usr/bin/python3
"""Speed of `occgt eval` (docs/EVAL.md; targets: 1500 pairs x 2000 matches in <= 30 s on
2 cores with LoFTR's protocol (issue 21), <= 60 s with `--protocol gluefactory`, its 8
estimator settings (issue 35)).

    tests/bench/eval_bench.py [--build build] [--scratch /tmp/occgt-eval-bench]
                              [--pairs 1500] [--matches 2000] [--reps 3] [--noise-px 0.5]
                              [--protocols loftr,gluefactory]

1. A synthetic split of --pairs pairs (occgt synth rooms at 640x480 through a demo-like
   recipe, written once into the scratch folder and reused).
2. Predictions per pair: --matches matches, 80 % inliers (visible pixels of image 0 warped
   with the shards' depth, plus --noise-px Gaussian noise in image 1) and 20 % random
   outliers. RANSAC's iterations, hence the time, grow fast as the noise nears the 0.5 px
   threshold (fewer points pass it): the figure depends on the predictions.
3. Per protocol of --protocols: `occgt eval --protocol P --threads 2` (and for loftr also
   `--threads 1`), --reps times each in alternation; medians of wall time. Baseline in the same run: tests/eval/reference.py's LoFTR-style Python loop
   (cv2, one process) on the same predictions, pose only, once; the ratios are printed.
"""
import argparse
import os
import statistics
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
SOURCE = os.path.normpath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, os.path.join(SOURCE, "tests", "eval"))
import predictions  # noqa: E402
import reference  # noqa: E402

RECIPE = """name: eval-bench
split: bench
seed: 0
resolution: [640, 480]
dataset:
  format: synthetic
  synthetic: {{scenes: {scenes}, frames: 40, width: 640, height: 480, seed: 1}}
  frame_stride: 1
  min_valid_depth_fraction: 0.3
labels:
  preset: default
patches: {{stride: 8, anchor: center, mutual: true}}
selection:
  max_frame_gap: 8
  pruning: {{max_distance_m: 3.0, max_view_angle_deg: 90, frustum: true}}
  score_stride: 8
  overlap: [0.3, 0.95]
  occlusion: [0.0, 1.0]
  aggregate: mean
  quota_per_scene: 25
occupancy:
  enabled: false
sample: {{image: none, depth: true, labels: true, occupancy: false}}
shards: {{samples_per_shard: 100}}
"""


def make_predictions(split, n_matches, noise_px, out):
    rng = np.random.default_rng(0)
    arrays = {}
    metas = {}
    for s in predictions.iter_samples(split):
        meta = s["json"]
        W, H = meta["resolution"]
        K0, K1, T = (np.array(meta[k]) for k in ("K0", "K1", "T_0to1"))
        vis = np.flatnonzero(s["label01.npy"].ravel() == 2)
        n_in = int(0.8 * n_matches)
        idx = rng.choice(vis, n_in, replace=len(vis) < n_in)
        v, u = np.divmod(idx, W)
        d = s["depth0.npy"].ravel()[idx]
        p = np.stack([(u - K0[0, 2]) / K0[0, 0] * d, (v - K0[1, 2]) / K0[1, 1] * d, d], 1)
        q = p @ T[:3, :3].T + T[:3, 3]
        x1 = np.stack([K1[0, 0] * q[:, 0] / q[:, 2] + K1[0, 2], K1[1, 1] * q[:, 1] / q[:, 2] + K1[1, 2]], 1)
        x1 = np.clip(x1 + rng.normal(0, noise_px, x1.shape), 0, [W - 1, H - 1])
        k0 = np.stack([u, v], 1).astype(np.float64)
        out0 = rng.uniform([0, 0], [W - 1, H - 1], (n_matches - n_in, 2))
        out1 = rng.uniform([0, 0], [W - 1, H - 1], (n_matches - n_in, 2))
        arrays[s["__key__"] + "/kpts0"] = np.r_[k0, out0].astype(np.float32)
        arrays[s["__key__"] + "/kpts1"] = np.r_[x1, out1].astype(np.float32)
        metas[s["__key__"]] = (K0, K1, T)
    np.savez(out, **arrays)
    return arrays, metas


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--build", default=os.path.join(SOURCE, "build"))
    ap.add_argument("--scratch", default="/tmp/occgt-eval-bench")
    ap.add_argument("--pairs", type=int, default=1500)
    ap.add_argument("--matches", type=int, default=2000)
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--noise-px", type=float, default=0.5)
    ap.add_argument("--protocols", default="loftr,gluefactory")
    ap.add_argument("--skip-reference", action="store_true", help="no Python baseline")
    args = ap.parse_args()
    binary = os.path.join(args.build, "apps", "occgt")
    os.makedirs(args.scratch, exist_ok=True)
    split = os.path.join(args.scratch, "split")
    if not os.path.exists(os.path.join(split, "index.json")):
        recipe = os.path.join(args.scratch, "recipe.yaml")
        with open(recipe, "w") as f:
            f.write(RECIPE.format(scenes=(args.pairs + 24) // 25))
        subprocess.run([binary, "build", "--json", recipe, "--out", split], check=True,
                       stdout=subprocess.DEVNULL)
    preds = os.path.join(args.scratch, f"pred_{args.matches}_{args.noise_px}.npz")
    arrays, metas = make_predictions(split, args.matches, args.noise_px, preds)
    print(f"split: {len(metas)} pairs, {args.matches} matches each, 80 % inliers with "
          f"{args.noise_px} px noise")
    runs = []
    for proto in args.protocols.split(","):
        runs += [(proto, "1"), (proto, "2")] if proto == "loftr" else [(proto, "2")]
    times = {run: [] for run in runs}
    for _ in range(args.reps):
        for proto, t in runs:
            t0 = time.perf_counter()
            subprocess.run([binary, "eval", split, "--predictions", preds, "--out",
                            os.path.join(args.scratch, f"eval_{proto}_t{t}.json"), "--threads", t,
                            "--protocol", proto], check=True, stdout=subprocess.DEVNULL)
            times[(proto, t)].append(time.perf_counter() - t0)
    ref = None
    if not args.skip_reference:
        t0 = time.perf_counter()
        for key, (K0, K1, T) in metas.items():
            reference.estimate_pose(arrays[key + "/kpts0"], arrays[key + "/kpts1"], K0, K1, 0.5,
                                    0.99999)
        ref = time.perf_counter() - t0
    for (proto, t), xs in times.items():
        m = statistics.median(xs)
        print(f"occgt eval --protocol {proto} --threads {t}: median {m:.2f} s "
              f"{sorted(round(x, 2) for x in xs)}; scaled to 1500 pairs "
              f"{m * 1500 / len(metas):.1f} s")
    if ref is not None and ("loftr", "2") in times:
        m2 = statistics.median(times[("loftr", "2")])
        print(f"python reference (cv2 loop, pose only, loftr): {ref:.2f} s; ratio reference / "
              f"loftr t2 = {ref / m2:.2f}")


if __name__ == "__main__":
    main()
