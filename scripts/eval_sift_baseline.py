#!/usr/bin/python3
"""Baseline predictions for `occgt eval`: OpenCV SIFT + Lowe's ratio test on every pair of
a split, written as one .npz keyed by sample key (docs/EVAL.md "A baseline").

    /usr/bin/python3 scripts/eval_sift_baseline.py SPLIT_DIR OUT.npz [--ratio 0.8]
        [--max-features 2000]

Reads image0/image1 (.png or .jpg) of each sample straight from the split's tar shards
(index.json order), so the keypoints are at the split's working resolution. A split built
without images (recipe sample.image: none) cannot be used. Needs NumPy and OpenCV >= 4.4
(SIFT in the main module): Debian's python3-opencv.
"""
import argparse
import json
import os
import sys
import tarfile
from typing import Dict, Tuple

import cv2
import numpy as np


def match_pair(img0: np.ndarray, img1: np.ndarray, sift: "cv2.SIFT", ratio: float
               ) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """kpts0, kpts1 float32 [N, 2] and confidence (1 - distance ratio) float32 [N]."""
    kp0, des0 = sift.detectAndCompute(img0, None)
    kp1, des1 = sift.detectAndCompute(img1, None)
    empty = np.zeros((0, 2), np.float32)
    if des0 is None or des1 is None or len(kp0) < 2 or len(kp1) < 2:
        return empty, empty, np.zeros(0, np.float32)
    knn = cv2.BFMatcher(cv2.NORM_L2).knnMatch(des0, des1, k=2)
    good = [m for m, n in (p for p in knn if len(p) == 2) if m.distance < ratio * n.distance]
    dist2 = {id(m): n.distance for m, n in (p for p in knn if len(p) == 2)}
    k0 = np.array([kp0[m.queryIdx].pt for m in good], np.float32).reshape(-1, 2)
    k1 = np.array([kp1[m.trainIdx].pt for m in good], np.float32).reshape(-1, 2)
    conf = np.array([1 - m.distance / max(dist2[id(m)], 1e-9) for m in good],
                    np.float32).reshape(-1)
    return k0, k1, conf


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("split_dir")
    parser.add_argument("out")
    parser.add_argument("--ratio", type=float, default=0.8, help="Lowe's ratio (default 0.8)")
    parser.add_argument("--max-features", type=int, default=2000,
                        help="SIFT features per image (default 2000)")
    args = parser.parse_args()
    cv2.setRNGSeed(0)
    sift = cv2.SIFT_create(nfeatures=args.max_features)
    with open(os.path.join(args.split_dir, "index.json")) as f:
        index = json.load(f)
    arrays: Dict[str, np.ndarray] = {}
    pairs = 0
    for shard in index["shardlist"]:
        images: Dict[str, Dict[str, bytes]] = {}
        with tarfile.open(os.path.join(args.split_dir, shard["url"]), "r:") as tar:
            for m in tar:
                folder, _, base = m.name.rpartition("/")
                stem, _, field = base.partition(".")
                if field.startswith("image0.") or field.startswith("image1."):
                    images.setdefault(folder + "/" + stem, {})[field[:6]] = tar.extractfile(m).read()
        for key, im in images.items():
            if set(im) != {"image0", "image1"}:
                print(f"{key}: missing image0/image1 member", file=sys.stderr)
                return 1
            g = [cv2.imdecode(np.frombuffer(im[k], np.uint8), cv2.IMREAD_GRAYSCALE)
                 for k in ("image0", "image1")]
            k0, k1, conf = match_pair(g[0], g[1], sift, args.ratio)
            arrays[key + "/kpts0"], arrays[key + "/kpts1"] = k0, k1
            arrays[key + "/confidence"] = conf
            pairs += 1
    if pairs == 0:
        print(f"{args.split_dir}: no sample with images (build with sample.image png or jpg)",
              file=sys.stderr)
        return 1
    tmp = args.out + ".tmp.npz"
    np.savez(tmp, **arrays)
    os.replace(tmp, args.out)
    print(f"{args.out}: SIFT + ratio {args.ratio} matches for {pairs} pairs")
    return 0


if __name__ == "__main__":
    sys.exit(main())
