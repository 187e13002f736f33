#!/usr/bin/python3
"""N-view items read from shards against computed on the fly, one core (docs/PERFORMANCE.md,
section "N views").

    PYTHONPATH=build/python /usr/bin/python3 tests/bench/tuple_shards_bench.py \\
        [--build build] [--reps 5] [--scratch /tmp/occgt-tuple-shards-bench]

Builds the N-view split of the shipped recipes/tartanair-tuples.yaml on the real TartanAir
sample (../shared/data; 640x480, tuples of 4-8 views, 16 tuples, deflate members) into the
scratch folder with BUILD/apps/occgt (reused when present), confines the process to one CPU
with torch and OpenCV on one thread, reads every shard once (page cache), then each
repetition times, in alternating order, every item of a fresh random permutation of:
  - shards: occgt.torch.TupleShardDataset(views)[i] (read, inflate, decode the PNGs,
    seen_by in C++);
  - computed: occgt.torch.TupleIndexDataset(tuples.jsonl, ...)[i] with the recipe's options
    (read the frames with occgt's reader, views_ground_truth: the same item, bit for bit).
Prints the median views per second of each (wall) and the ratio shards / computed.
"""
from __future__ import annotations

import argparse
import os
import random
import statistics
import subprocess
import sys
import time
from typing import Any, Dict, List

SOURCE = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--build", default=os.path.join(SOURCE, "build"))
    p.add_argument("--reps", type=int, default=5)
    p.add_argument("--scratch", default="/tmp/occgt-tuple-shards-bench")
    args = p.parse_args()
    shared = os.environ.get("OCCGT_SHARED_DATA", os.path.join(SOURCE, "..", "shared", "data"))
    root = os.path.join(shared, "tartanair", "hospital_sample")
    if not os.path.isdir(root):
        sys.exit(f"tuple_shards_bench: real sample data missing: {root}")
    recipe = os.path.join(SOURCE, "recipes", "tartanair-tuples.yaml")
    out = args.scratch
    if not os.path.exists(os.path.join(out, "views", "index.json")):
        env = dict(os.environ, OCCGT_SHARED_DATA=shared)
        binary = os.path.join(args.build, "apps", "occgt")
        for cmd in (["covis", recipe, "--out", out], ["tuples", recipe, "--out", out, "--shards"]):
            subprocess.run([binary, *cmd], check=True, env=env, stdout=subprocess.DEVNULL)
    os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
    import cv2
    import torch

    torch.set_num_threads(1)
    cv2.setNumThreads(1)
    from occgt.torch import TupleIndexDataset, TupleShardDataset

    stored = TupleShardDataset(os.path.join(out, "views"))
    computed = TupleIndexDataset(os.path.join(out, "tuples.jsonl"), root, "tartanair",
                                 width=640, height=480, preset="default", seed=0,
                                 dataset_max_depth_m=100.0)
    views = [len(t.frame_ids) for t in computed.tuples]
    for i in range(len(stored)):  # page cache, readers opened
        stored[i]
    computed[0]
    rates: Dict[str, List[float]] = {"shards": [], "computed": []}
    rng = random.Random(0)
    for rep in range(args.reps):
        order = list(rates) if rep % 2 == 0 else list(reversed(rates))
        for name in order:
            ds: Any = stored if name == "shards" else computed
            perm = list(range(len(ds)))
            rng.shuffle(perm)
            t0 = time.perf_counter()
            for i in perm:
                ds[i]
            rates[name].append(sum(views) / (time.perf_counter() - t0))
        print(f"rep {rep}: " + ", ".join(f"{k} {v[-1]:.1f} views/s" for k, v in rates.items()))
    med = {k: statistics.median(v) for k, v in rates.items()}
    print(f"{len(stored)} tuples, {sum(views)} views of 640x480 (4-8 a tuple), one core")
    for k, v in med.items():
        print(f"{k}: median {v:.1f} views/s ({1000 / v:.2f} ms a view)")
    print(f"ratio shards / computed: {med['shards'] / med['computed']:.2f}")


if __name__ == "__main__":
    main()
