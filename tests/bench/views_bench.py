#!/usr/bin/python3
"""N-view ground truth from Python: occgt.views_ground_truth of 8 views of the real 7-Scenes
sample at 640x480 (all 56 directions i != j, the diagonal from the depth masks, 512 tracks),
against the 28 occgt.pair_ground_truth calls that label the same 56 directions
(docs/PERFORMANCE.md, section "N views").

    taskset -c 0 env PYTHONPATH=build/python /usr/bin/python3 tests/bench/views_bench.py \\
        [--data ../shared/data] [--reps 21]

Prints the median wall and CPU time (time.process_time) of each and their ratio.

    /usr/bin/python3 tests/bench/views_bench.py --base OLD/python [--case views] [--reps 41]

Before/after on the same machine state: two worker processes on CPU 0, one importing occgt
from build/python, one from OLD/python (another build's python folder), called in turn, one
call each, so that both see the same load; prints each one's median wall time and the ratio
new / old.
"""
from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time
from typing import Callable, Dict, List

SOURCE = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def cases(data: str) -> Dict[str, Callable[[], object]]:
    import occgt  # the one on sys.path: build/python, or a worker's folder

    ds = occgt.open_dataset(os.path.join(data, "sevenscenes"), "sevenscenes")
    scene = ds.scene(ds.scenes()[0])
    ids = [f.id for f in scene.frames if f.usable][::6][:8]
    if len(ids) != 8:
        sys.exit(f"expected 8 usable frames, got {len(ids)}")
    frames = [scene.load(i) for i in ids]
    depths = [f[0] for f in frames]
    Ks = [f[1] for f in frames]
    poses = [f[2] for f in frames]
    rng = (scene.min_depth_m, scene.max_depth_m)

    def views() -> object:
        return occgt.views_ground_truth(depths, Ks, poses, num_tracks=512,
                                        dataset_depth_range=rng)

    def pairs() -> object:
        return [occgt.pair_ground_truth(depths[i], depths[j], Ks[i], Ks[j], poses[i], poses[j],
                                        dataset_depth_range=rng)
                for i in range(8) for j in range(i + 1, 8)]

    return {"views": views, "pairs": pairs}


def worker(data: str, case: str) -> int:
    """One call of `case` per line read; prints its wall seconds."""
    f = cases(data)[case]
    f()  # warm up
    for _ in sys.stdin:
        t0 = time.perf_counter()
        f()
        print(time.perf_counter() - t0, flush=True)
    return 0


def before_after(args: argparse.Namespace) -> int:
    folders = {"new": os.path.join(SOURCE, "build", "python"), "old": args.base}
    procs = {}
    for name, folder in folders.items():
        env = dict(os.environ, PYTHONPATH=folder)
        procs[name] = subprocess.Popen(
            ["taskset", "-c", "0", sys.executable, os.path.abspath(__file__), "--worker",
             "--case", args.case, "--data", args.data],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, env=env)
    wall: Dict[str, List[float]] = {k: [] for k in procs}
    for _ in range(args.reps):
        for name, p in procs.items():
            assert p.stdin is not None and p.stdout is not None
            p.stdin.write("go\n")
            p.stdin.flush()
            wall[name].append(float(p.stdout.readline()))
    for p in procs.values():
        assert p.stdin is not None
        p.stdin.close()
        p.wait()
    for name in procs:
        print(f"{args.case} {name}: wall {1e3 * statistics.median(wall[name]):.2f} ms "
              f"(min {1e3 * min(wall[name]):.2f}) [{folders[name]}]")
    print(f"new/old (wall medians): "
          f"{statistics.median(wall['new']) / statistics.median(wall['old']):.3f}")
    return 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", default=os.path.join(os.path.dirname(SOURCE), "shared", "data"))
    ap.add_argument("--reps", type=int, default=21)
    ap.add_argument("--base", help="another build's python folder: before/after")
    ap.add_argument("--case", choices=["views", "pairs"], default="views")
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker:
        return worker(args.data, args.case)
    if args.base:
        return before_after(args)
    fs = cases(args.data)
    wall: Dict[str, List[float]] = {k: [] for k in fs}
    cpu: Dict[str, List[float]] = {k: [] for k in fs}
    for f in fs.values():  # warm up
        f()
    for _ in range(args.reps):
        for k, f in fs.items():
            w0, c0 = time.perf_counter(), time.process_time()
            f()
            wall[k].append(time.perf_counter() - w0)
            cpu[k].append(time.process_time() - c0)
    for k in fs:
        print(f"{k}: wall {1e3 * statistics.median(wall[k]):.2f} ms "
              f"(min {1e3 * min(wall[k]):.2f}), cpu {1e3 * statistics.median(cpu[k]):.2f} ms")
    print(f"pairs/views (wall medians): "
          f"{statistics.median(wall['pairs']) / statistics.median(wall['views']):.2f}x")
    return 0


if __name__ == "__main__":
    sys.exit(main())
