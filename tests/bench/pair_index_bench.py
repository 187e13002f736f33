#!/usr/bin/python3
"""A LoFTR-layout pair index of N rows read with occgt.torch.read_pair_index, the way
PairIndexDataset holds it, or a tuples.jsonl of N tuples read the way TupleIndexDataset holds
it (docs/PERFORMANCE.md, section "Pair and tuple indices at scale").

    PYTHONPATH=build/python /usr/bin/python3 tests/bench/pair_index_bench.py \\
        [--pairs 10000000 | --tuples 1000000 [--views 8]] [--reps 3] [--against DIR] \\
        [--scratch /tmp/occgt-pair-index-bench]

Writes the index into the scratch folder (reused when present): for pairs, one npz (``name``
int64 [N, 4]: 700 scenes with sub-scene 0, frame numbers below 6000, as LoFTR's ScanNet
scene_info; ``score`` float32); with --tuples, one tuples.jsonl as ``occgt tuples`` writes it
(700 scenes, --views distinct frame ids ``%06d`` below 6000 a line, a --views × --views
covisibility matrix of random float32 values). Then, in a fresh process per repetition, it
reports for the package on PYTHONPATH and, with --against DIR, for the package in DIR (e.g. an
older build's build/python), one after the other:
  - read: CPU seconds of read_pair_index, or of the tuples.jsonl reader TupleIndexDataset
    calls (occgt.torch.tuples._read_tuple_lines: before the TupleIndex, a list of TupleRef
    and a list of "<path>:<line>" strings, both held) (time.process_time);
  - held: VmRSS after reading, less VmRSS before, after gc (/proc/self/status), in bytes
    per pair or tuple; and the same after malloc_trim(0) (at the end), without the freed
    memory glibc's heap keeps (the reader's temporaries);
  - forked: a forked child (a DataLoader worker) reads every 16th entry of the index (a
    tuple's scene and each of its frame ids, as TupleIndexDataset's item does); the
    memory it copied from its parent (Private_Dirty of /proc/self/smaps_rollup, after less
    before), in bytes per entry of the index.
Prints each repetition and the medians, and with --against the ratios of the medians
(PYTHONPATH's / DIR's).
"""
from __future__ import annotations

import argparse
import io
import json
import os
import statistics
import subprocess
import sys
from typing import Dict, List

CHILD = r"""
import ctypes, gc, json, os, sys, time
sys.path.insert(0, sys.argv[2])
if sys.argv[3] == "pairs":
    from occgt.torch import read_pair_index as read
else:
    from occgt.torch.tuples import _read_tuple_lines as read

def status(field, path="/proc/self/status"):
    with open(path) as f:
        for line in f:
            if line.startswith(field + ":"):
                return int(line.split()[1]) * 1024
    raise SystemExit(f"{path}: no {field}")

gc.collect()
before = status("VmRSS")
start = time.process_time()
index = read(sys.argv[1])
read_s = time.process_time() - start
gc.collect()
held = status("VmRSS") - before
entries = index[0] if isinstance(index, tuple) else index  # tuples before: (refs, where)
n = len(entries)
r, w = os.pipe()
pid = os.fork()
if pid == 0:
    os.close(r)
    dirty = status("Private_Dirty", "/proc/self/smaps_rollup")
    scenes, views = set(), 0
    for k in range(0, n, 16):
        ref = entries[k]
        scenes.add(ref.scene)
        for frame_id in getattr(ref, "frame_ids", ()):  # a TupleRef's, as an item reads them
            views += len(frame_id)
    copied = status("Private_Dirty", "/proc/self/smaps_rollup") - dirty
    os.write(w, json.dumps([copied, len(scenes)]).encode())
    os._exit(0)
os.close(w)
copied, scenes = json.loads(os.read(r, 1000))
os.waitpid(pid, 0)
ctypes.CDLL(None).malloc_trim(0)
trimmed = status("VmRSS") - before
print(json.dumps({"entries": n, "read_s": read_s, "held_b": held / n, "forked_b": copied / n,
                  "trimmed_b": trimmed / n}))
"""


def run(index: str, package: str, kind: str) -> Dict[str, float]:
    out = subprocess.run([sys.executable, "-c", CHILD, index, package, kind], check=True,
                         capture_output=True, text=True).stdout
    return json.loads(out)


def write_pairs(path: str, n: int) -> None:
    """A LoFTR ScanNet scene_info npz of n pairs."""
    import numpy as np  # pylint: disable=import-outside-toplevel

    rng = np.random.default_rng(0)
    name = np.stack([rng.integers(0, 700, n), np.zeros(n, np.int64),
                     rng.integers(0, 6000, n), rng.integers(0, 6000, n)], 1)
    np.savez(path + ".tmp.npz", name=name, score=rng.random(n).astype(np.float32))
    os.replace(path + ".tmp.npz", path)


def write_tuples(path: str, n: int, views: int) -> None:
    """n lines of ``occgt tuples``' tuples.jsonl (keys sorted, float32 covisibility printed
    as doubles, as its writer does), in chunks of rows."""
    import numpy as np  # pylint: disable=import-outside-toplevel

    rng = np.random.default_rng(0)
    with open(path + ".tmp", "w") as f:
        for begin in range(0, n, 100_000):
            rows = min(100_000, n - begin)
            scene = rng.integers(0, 700, rows)
            frames = rng.integers(0, 6000, (rows, views))
            while True:  # distinct ids in each row: draw the rows with a repeat again
                ordered = np.sort(frames, axis=1)
                again = (ordered[:, 1:] == ordered[:, :-1]).any(axis=1)
                if not again.any():
                    break
                frames[again] = rng.integers(0, 6000, (int(again.sum()), views))
            covisibility = rng.random((rows, views, views), dtype=np.float32).astype(np.float64)
            out = io.StringIO()
            for s, ids, c in zip(scene.tolist(), frames.tolist(), covisibility.tolist()):
                out.write(json.dumps({"covisibility": c,
                                      "frame_ids": [f"{i:06d}" for i in ids],
                                      "scene": f"scene{s:04d}_00"}, separators=(",", ":")))
                out.write("\n")
            f.write(out.getvalue())
    os.replace(path + ".tmp", path)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--pairs", type=int, default=10_000_000)
    parser.add_argument("--tuples", type=int, help="a tuples.jsonl of this many tuples instead")
    parser.add_argument("--views", type=int, default=8, help="views a tuple (with --tuples)")
    parser.add_argument("--reps", type=int, default=3)
    parser.add_argument("--against", help="another package folder (holding occgt/)")
    parser.add_argument("--scratch", default="/tmp/occgt-pair-index-bench")
    args = parser.parse_args()

    os.makedirs(args.scratch, exist_ok=True)
    kind = "pairs" if args.tuples is None else "tuples"
    if kind == "tuples":
        index = os.path.join(args.scratch, f"tuples_{args.tuples}x{args.views}.jsonl")
        if not os.path.exists(index):
            write_tuples(index, args.tuples, args.views)
    else:
        index = os.path.join(args.scratch, f"scene_info_{args.pairs}.npz")
        if not os.path.exists(index):
            write_pairs(index, args.pairs)
    here = next((p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p), ".")
    packages = {"PYTHONPATH": os.path.abspath(here)}
    if args.against:
        packages["against"] = os.path.abspath(args.against)
    runs: Dict[str, List[Dict[str, float]]] = {k: [] for k in packages}
    for rep in range(args.reps):
        for label, package in packages.items():
            r = run(index, package, kind)
            runs[label].append(r)
            print(f"rep {rep} {label}: {r['entries']} {kind}, read {r['read_s']:.2f} CPU s, held "
                  f"{r['held_b']:.1f} B/{kind[:-1]} ({r['trimmed_b']:.1f} after malloc_trim), "
                  f"forked child copied {r['forked_b']:.1f} B/{kind[:-1]}", flush=True)
    medians = {label: {k: statistics.median(r[k] for r in rs)
                       for k in ("read_s", "held_b", "trimmed_b", "forked_b")}
               for label, rs in runs.items()}
    for label, m in medians.items():
        print(f"median {label} ({packages[label]}): read {m['read_s']:.2f} CPU s, held "
              f"{m['held_b']:.1f} B/{kind[:-1]} ({m['trimmed_b']:.1f} after malloc_trim), "
              f"forked child copied {m['forked_b']:.1f} B/{kind[:-1]}")
    if args.against:
        a, b = medians["PYTHONPATH"], medians["against"]
        print("ratios PYTHONPATH/against: " + ", ".join(
            f"{k} {a[k] / b[k]:.3f}" if b[k] else f"{k} -" for k in a))


if __name__ == "__main__":
    main()
