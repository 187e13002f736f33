#!/usr/bin/python3
"""sample.compression on the real samples: bytes per sample, build time and ShardDataset reads,
none against deflate (docs/PERFORMANCE.md, section "Sample compression").

    PYTHONPATH=build/python /usr/bin/python3 tests/bench/compression_bench.py \\
        [--build build] [--reps 7] [--scratch /tmp/occgt-compression-bench]

For recipes/sevenscenes-sample.yaml and recipes/tartanair-sample.yaml (data from
OCCGT_SHARED_DATA, default ../shared/data), writes two variants into the scratch folder,
`compression: none` and `compression: deflate`, and then, per repetition in alternating
order, builds each into a fresh folder with `--threads 2` (wall time and the CPU time of the
process, os.wait4). Bytes per sample = shard bytes / samples from index.json. Then, with the
process on one CPU and torch/OpenCV on one thread, every shard in the page cache, reads every
sample of each split through ShardDataset in a random order, with and without images
(samples per CPU second). Prints medians and the ratios deflate / none.
"""
from __future__ import annotations

import argparse
import json
import os
import random
import shutil
import statistics
import subprocess
import sys
import time
from typing import Dict, List, Tuple

SOURCE = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
RECIPES = ("sevenscenes-sample", "tartanair-sample")
MODES = ("none", "deflate")


def variant(recipe: str, mode: str, scratch: str) -> str:
    with open(os.path.join(SOURCE, "recipes", recipe + ".yaml")) as f:
        text = f.read()
    old = "occupancy: true}"
    assert text.count(old) == 1, f"{recipe}.yaml: expected one 'sample: {{... {old}' line"
    path = os.path.join(scratch, f"{recipe}-{mode}.yaml")
    with open(path, "w") as f:
        f.write(text.replace(old, f"occupancy: true, compression: {mode}}}"))
    return path


def build(occgt: str, recipe: str, out: str) -> Tuple[float, float]:
    """(wall s, CPU s) of one `occgt build` into a fresh folder."""
    shutil.rmtree(out, ignore_errors=True)
    env = dict(os.environ)
    env.setdefault("OCCGT_SHARED_DATA", os.path.join(SOURCE, "..", "shared", "data"))
    t0 = time.perf_counter()
    with open(out + ".log", "w+") as log:
        proc = subprocess.Popen([occgt, "build", recipe, "--out", out, "--threads", "2"],
                                stdout=log, stderr=log, env=env)
        _, status, usage = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - t0
        if status != 0:
            log.seek(0)
            sys.exit(f"{recipe}: occgt build failed ({status}):\n{log.read()}")
    return wall, usage.ru_utime + usage.ru_stime


def bytes_per_sample(split: str) -> float:
    with open(os.path.join(split, "index.json")) as f:
        shards = json.load(f)["shardlist"]
    return sum(s["filesize"] for s in shards) / sum(s["nsamples"] for s in shards)


def read_rates(split: str, reps: int) -> Dict[str, float]:
    """Median samples per CPU second of random ShardDataset reads, images off and on."""
    from occgt.torch import ShardDataset

    for name in os.listdir(split):
        if name.endswith(".tar"):
            with open(os.path.join(split, name), "rb") as f:
                f.read()
    out = {}
    for images in (False, True):
        ds = ShardDataset(split, occupancy="words", images=images)
        rng = random.Random(0)
        rates = []
        for _ in range(reps):
            order = list(range(len(ds)))
            rng.shuffle(order)
            c0 = time.process_time()
            for i in order:
                ds[i]
            rates.append(len(order) / (time.process_time() - c0))
        out["images" if images else "arrays"] = statistics.median(rates)
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build", default=os.path.join(SOURCE, "build"))
    ap.add_argument("--reps", type=int, default=7)
    ap.add_argument("--scratch", default="/tmp/occgt-compression-bench")
    args = ap.parse_args()
    occgt = os.path.join(args.build, "apps", "occgt")
    os.makedirs(args.scratch, exist_ok=True)
    print(f"load {os.getloadavg()[0]:.1f}")

    times: Dict[Tuple[str, str], List[Tuple[float, float]]] = {}
    for rep in range(args.reps):
        for recipe in RECIPES:
            modes = MODES if rep % 2 == 0 else MODES[::-1]
            for mode in modes:
                out = os.path.join(args.scratch, f"{recipe}-{mode}")
                times.setdefault((recipe, mode), []).append(
                    build(occgt, variant(recipe, mode, args.scratch), out))

    os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})
    import cv2
    import torch

    torch.set_num_threads(1)
    cv2.setNumThreads(1)
    for recipe in RECIPES:
        row = {}
        for mode in MODES:
            split = os.path.join(args.scratch, f"{recipe}-{mode}")
            wall = statistics.median(t[0] for t in times[(recipe, mode)])
            cpu = statistics.median(t[1] for t in times[(recipe, mode)])
            row[mode] = {"bytes": bytes_per_sample(split), "wall": wall, "cpu": cpu,
                         **read_rates(split, args.reps)}
            r = row[mode]
            print(f"{recipe} {mode}: {r['bytes'] / 1e6:.2f} MB/sample, build wall {wall:.2f} s "
                  f"cpu {cpu:.2f} s, ShardDataset {r['arrays']:.0f}/s arrays, "
                  f"{r['images']:.0f}/s with images (per CPU second)")
        d, n = row["deflate"], row["none"]
        print(f"{recipe} deflate/none: bytes {d['bytes'] / n['bytes']:.2f}, build wall "
              f"{d['wall'] / n['wall']:.2f} cpu {d['cpu'] / n['cpu']:.2f}, reads arrays "
              f"{d['arrays'] / n['arrays']:.2f} images {d['images'] / n['images']:.2f}")
    print(f"load {os.getloadavg()[0]:.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
