#!/usr/bin/python3
"""Random reads of occgt.torch.ShardDataset from the page cache, one core (docs/PERFORMANCE.md,
section "Reading shards from Python").

    PYTHONPATH=build/python /usr/bin/python3 tests/bench/shard_dataset_bench.py \\
        [--build build] [--split DIR] [--reps 7] [--scratch /tmp/occgt-shard-dataset-bench]

Without --split, builds a 640x480 synthetic split (recipes/demo.yaml at 640x480: labels,
cells, matches, packed occupancy words, PNG images, float32 depth; 48 samples; plain .npy
members, sample.compression: none: tests/bench/compression_bench.py compares deflate) into the
scratch folder with BUILD/apps/occgt (reused when present). The process is confined to one
CPU (sched_setaffinity) with torch and OpenCV on one thread, and every shard is read once
before timing (page cache). Each repetition times, in a rotating order:
  - shard_dataset: ShardDataset(occupancy="words", images=False)[i] for every i of a fresh
    random permutation (tensors of every array of the sample contract);
  - shard_dataset_images: the same with images=True (two PNG decodes + grey per sample);
  - tarfile: the plain NumPy reader of docs/READING_SHARDS.md (executed from the page)
    over the same split, in shard order (its best case: tarfile cannot seek to a sample);
  - index: ShardDataset(split) constructed --index-reps times (index.json and one pass over
    every shard's tar headers: the byte range of every member), samples indexed.
Prints samples per wall second and per CPU second (time.process_time: what the process
itself used, less inflated by other processes on a shared machine) for each repetition, the
medians and the ratios shard_dataset / tarfile of the medians, and the index's CPU time per
construction. Only the public API is used, so the same script measures another checkout's
package (PYTHONPATH) on the same split.
"""
from __future__ import annotations

import argparse
import json
import os
import random
import re
import statistics
import subprocess
import sys
import time
from typing import Any, Callable, Dict, List

SOURCE = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def bench_recipe(path: str) -> None:
    with open(os.path.join(SOURCE, "recipes", "demo.yaml")) as f:
        text = f.read()
    text = text.replace("resolution: [320, 240]", "resolution: [640, 480]")
    text = text.replace("width: 320, height: 240", "width: 640, height: 480")
    text = text.replace("quota_per_scene: 12", "quota_per_scene: 24")
    text = text.replace("frames: 16", "frames: 30")
    text = text.replace("occupancy: true}", "occupancy: true, compression: none}")
    assert "[640, 480]" in text and "quota_per_scene: 24" in text and "none}" in text, \
        "demo.yaml changed"
    with open(path, "w") as f:
        f.write(text)


def doc_reader() -> Dict[str, Any]:
    with open(os.path.join(SOURCE, "docs", "READING_SHARDS.md")) as f:
        text = f.read()
    m = re.search(r"<!-- reader:numpy -->\s*```python\n(.*?)```\s*<!-- /reader:numpy -->", text,
                  re.S)
    assert m is not None, "docs/READING_SHARDS.md: no reader block"
    namespace: Dict[str, Any] = {}
    exec(compile(m.group(1), "READING_SHARDS.md:reader", "exec"), namespace)
    return namespace


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build", default=os.path.join(SOURCE, "build"))
    ap.add_argument("--split", help="an existing split folder (default: build one)")
    ap.add_argument("--reps", type=int, default=7)
    ap.add_argument("--scratch", default="/tmp/occgt-shard-dataset-bench")
    ap.add_argument("--index-reps", type=int, default=20,
                    help="constructions of ShardDataset timed per repetition of 'index'")
    args = ap.parse_args()

    split = args.split
    if split is None:
        split = os.path.join(args.scratch, "split")
        if not os.path.exists(os.path.join(split, "index.json")):
            os.makedirs(args.scratch, exist_ok=True)
            recipe = os.path.join(args.scratch, "bench.yaml")
            bench_recipe(recipe)
            subprocess.run([os.path.join(args.build, "apps", "occgt"), "build", recipe, "--out",
                            split], check=True, stdout=subprocess.DEVNULL)

    os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})
    import cv2
    import torch

    from occgt.torch import ShardDataset

    torch.set_num_threads(1)
    cv2.setNumThreads(1)
    with open(os.path.join(split, "index.json")) as f:
        shards = [os.path.join(split, s["url"]) for s in json.load(f)["shardlist"]]
    total_bytes = 0
    for path in shards:  # into the page cache
        with open(path, "rb") as f:
            total_bytes += len(f.read())

    words = ShardDataset(split, occupancy="words", images=False)
    images = ShardDataset(split, occupancy="words", images=True)
    reader = doc_reader()
    n = len(words)
    first = words[0]
    print(f"split {split}: {n} samples, {total_bytes / n / 1e6:.2f} MB per sample, "
          f"label01 {tuple(first['label01'].shape)}, occ0 {first['occ0'].dtype}; "
          f"load {os.getloadavg()[0]:.1f}")
    rng = random.Random(0)

    def random_reads(ds: ShardDataset) -> Callable[[], int]:
        def run() -> int:
            order = list(range(n))
            rng.shuffle(order)
            for i in order:
                ds[i]
            return n
        return run

    def tarfile_reads() -> int:
        return sum(1 for _ in reader["iter_split"](split))

    def index_split() -> int:
        for _ in range(args.index_reps):
            ShardDataset(split, occupancy="words", images=False)
        return n * args.index_reps

    runs: Dict[str, Callable[[], int]] = {"shard_dataset": random_reads(words),
                                          "shard_dataset_images": random_reads(images),
                                          "tarfile": tarfile_reads,
                                          "index": index_split}
    names = list(runs)
    wall: Dict[str, List[float]] = {k: [] for k in names}
    cpu: Dict[str, List[float]] = {k: [] for k in names}
    for rep in range(args.reps):
        for name in names[rep % len(names):] + names[:rep % len(names)]:
            t0, c0 = time.perf_counter(), time.process_time()
            count = runs[name]()
            wall[name].append(count / (time.perf_counter() - t0))
            cpu[name].append(count / (time.process_time() - c0))
        print(f"rep {rep}: " + ", ".join(f"{k} {wall[k][-1]:.0f}/s wall {cpu[k][-1]:.0f}/s cpu"
                                         for k in names))
    for what, rates in (("wall", wall), ("cpu", cpu)):
        med = {k: statistics.median(v) for k, v in rates.items()}
        print(f"medians, samples per {what} second: " + ", ".join(
            f"{k} {v:.0f} ({min(rates[k]):.0f}-{max(rates[k]):.0f})" for k, v in med.items()))
        print(f"  ratio shard_dataset / tarfile {med['shard_dataset'] / med['tarfile']:.2f}, "
              f"shard_dataset_images / tarfile {med['shard_dataset_images'] / med['tarfile']:.2f}")
        print(f"  index: {1e3 * n / med['index']:.2f} ms per ShardDataset({len(shards)} shards, "
              f"{n} samples), {1e6 / med['index']:.1f} us per sample")
    print(f"load {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    sys.exit(main())
