#!/usr/bin/python3
"""N-view ground truth from Python: occgt.views_ground_truth of 8 views of the real 7-Scenes
sample at 640x480 (all 56 directions i != j, the diagonal from the depth masks, 512 tracks),
against the 28 occgt.pair_ground_truth calls that label the same 56 directions (docs/PERFORMANCE.md,
section "N-view ground truth").

    taskset -c 0 env PYTHONPATH=build/python /usr/bin/python3 tests/bench/views_bench.py \\
        [--data ../shared/data] [--reps 21]

Prints the median wall and CPU time (time.process_time) of each and their ratio.
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from typing import Callable, Dict, List

import occgt

SOURCE = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", default=os.path.join(os.path.dirname(SOURCE), "shared", "data"))
    ap.add_argument("--reps", type=int, default=21)
    args = ap.parse_args()
    ds = occgt.open_dataset(os.path.join(args.data, "sevenscenes"), "sevenscenes")
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

    cases: Dict[str, Callable[[], object]] = {"views": views, "pairs": pairs}
    wall: Dict[str, List[float]] = {k: [] for k in cases}
    cpu: Dict[str, List[float]] = {k: [] for k in cases}
    for f in cases.values():  # warm up
        f()
    for _ in range(args.reps):
        for k, f in cases.items():
            w0, c0 = time.perf_counter(), time.process_time()
            f()
            wall[k].append(time.perf_counter() - w0)
            cpu[k].append(time.process_time() - c0)
    for k in cases:
        print(f"{k}: wall {1e3 * statistics.median(wall[k]):.2f} ms "
              f"(min {1e3 * min(wall[k]):.2f}), cpu {1e3 * statistics.median(cpu[k]):.2f} ms")
    print(f"pairs/views (wall medians): "
          f"{statistics.median(wall['pairs']) / statistics.median(wall['views']):.2f}x")
    return 0


if __name__ == "__main__":
    sys.exit(main())
