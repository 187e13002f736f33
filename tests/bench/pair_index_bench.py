#!/usr/bin/python3
"""A LoFTR-layout pair index of N rows read with occgt.torch.read_pair_index, the way
PairIndexDataset holds it (docs/PERFORMANCE.md, section "Pair index at scale").

    PYTHONPATH=build/python /usr/bin/python3 tests/bench/pair_index_bench.py \\
        [--pairs 10000000] [--reps 3] [--against DIR] [--scratch /tmp/occgt-pair-index-bench]

Writes one npz (``name`` int64 [N, 4]: 700 scenes with sub-scene 0, frame numbers below 6000,
as LoFTR's ScanNet scene_info; ``score`` float32) into the scratch folder (reused when
present), then, in a fresh process per repetition, reports for the package on PYTHONPATH and,
with --against DIR, for the package in DIR (e.g. an older build's build/python), one after
the other:
  - read: CPU seconds of read_pair_index (time.process_time);
  - held: VmRSS after reading, less VmRSS before, after gc (/proc/self/status), in bytes
    per pair;
  - forked: a forked child (a DataLoader worker) reads every 16th pair of the index; the
    memory it copied from its parent (Private_Dirty of /proc/self/smaps_rollup, after less
    before), in bytes per pair of the index.
Prints each repetition and the medians, and with --against the ratios of the medians
(PYTHONPATH's / DIR's).
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from typing import Dict, List

CHILD = r"""
import gc, json, os, sys, time
sys.path.insert(0, sys.argv[2])
from occgt.torch import read_pair_index

def status(field, path="/proc/self/status"):
    with open(path) as f:
        for line in f:
            if line.startswith(field + ":"):
                return int(line.split()[1]) * 1024
    raise SystemExit(f"{path}: no {field}")

gc.collect()
before = status("VmRSS")
start = time.process_time()
index = read_pair_index(sys.argv[1])
read_s = time.process_time() - start
gc.collect()
held = status("VmRSS") - before
n = len(index)
r, w = os.pipe()
pid = os.fork()
if pid == 0:
    os.close(r)
    dirty = status("Private_Dirty", "/proc/self/smaps_rollup")
    scenes = set()
    for k in range(0, n, 16):
        scenes.add(index[k].scene)
    copied = status("Private_Dirty", "/proc/self/smaps_rollup") - dirty
    os.write(w, json.dumps([copied, len(scenes)]).encode())
    os._exit(0)
os.close(w)
copied, scenes = json.loads(os.read(r, 1000))
os.waitpid(pid, 0)
print(json.dumps({"pairs": n, "read_s": read_s, "held_b": held / n, "forked_b": copied / n}))
"""


def run(index: str, package: str) -> Dict[str, float]:
    out = subprocess.run([sys.executable, "-c", CHILD, index, package], check=True,
                         capture_output=True, text=True).stdout
    return json.loads(out)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--pairs", type=int, default=10_000_000)
    parser.add_argument("--reps", type=int, default=3)
    parser.add_argument("--against", help="another package folder (holding occgt/)")
    parser.add_argument("--scratch", default="/tmp/occgt-pair-index-bench")
    args = parser.parse_args()
    import numpy as np  # pylint: disable=import-outside-toplevel

    os.makedirs(args.scratch, exist_ok=True)
    index = os.path.join(args.scratch, f"scene_info_{args.pairs}.npz")
    if not os.path.exists(index):
        rng = np.random.default_rng(0)
        n = args.pairs
        name = np.stack([rng.integers(0, 700, n), np.zeros(n, np.int64),
                         rng.integers(0, 6000, n), rng.integers(0, 6000, n)], 1)
        np.savez(index + ".tmp.npz", name=name, score=rng.random(n).astype(np.float32))
        os.replace(index + ".tmp.npz", index)
    here = next((p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p), ".")
    packages = {"PYTHONPATH": os.path.abspath(here)}
    if args.against:
        packages["against"] = os.path.abspath(args.against)
    runs: Dict[str, List[Dict[str, float]]] = {k: [] for k in packages}
    for rep in range(args.reps):
        for label, package in packages.items():
            r = run(index, package)
            runs[label].append(r)
            print(f"rep {rep} {label}: {r['pairs']} pairs, read {r['read_s']:.2f} CPU s, held "
                  f"{r['held_b']:.1f} B/pair, forked child copied {r['forked_b']:.1f} B/pair",
                  flush=True)
    medians = {label: {k: statistics.median(r[k] for r in rs) for k in ("read_s", "held_b",
                                                                        "forked_b")}
               for label, rs in runs.items()}
    for label, m in medians.items():
        print(f"median {label} ({packages[label]}): read {m['read_s']:.2f} CPU s, held "
              f"{m['held_b']:.1f} B/pair, forked child copied {m['forked_b']:.1f} B/pair")
    if args.against:
        a, b = medians["PYTHONPATH"], medians["against"]
        print("ratios PYTHONPATH/against: " + ", ".join(
            f"{k} {a[k] / b[k]:.3f}" if b[k] else f"{k} -" for k in a))


if __name__ == "__main__":
    main()
