#!/usr/bin/python3
"""On-the-fly supervision of one 640x480 pair from Python against LoFTR-style supervision in
torch, side by side in one run (docs/PERFORMANCE.md, section "Supervision from Python").

    taskset -c 0 env PYTHONPATH=build/python /usr/bin/python3 tests/bench/supervision_bench.py \\
        [--data ../shared/data] [--reps 25]

One pair of the real 7-Scenes sample (000150, 000160) at 640x480, as a batch of one. torch on
one thread (torch.set_num_threads(1)), CPU. Each repetition times, in a rotating order:
  a  occgt.pair_ground_truth (labels both ways, both metrics, vv/vo/ov matches; no occupancy);
  b  occgt.torch.loftr_supervision(batch, "occ2net") (a + tensors, fine targets, per-type
     index sets), with dense_conf_matrix=False (b) and True (b_dense, the [1, 4800, 4800]
     float32 matrix LoFTR's loss reads);
  c  the torch re-implementation of LoFTR's spvs_coarse of tests/python/supervision_test.py in
     LoFTR's float32 (grid, both-way warps, nearest cells, loop-back, the dense
     conf_matrix_gt, ids), its baseline;
  c_ids  the same without the dense matrix (the baseline of d);
  d  occgt.torch.loftr_supervision(batch) (mode "loftr"), dense_conf_matrix=True (d_dense)
     and False (d).
Prints the median wall and CPU time (time.process_time) of each, and the ratios of the
medians c/a, c/b, c/d_dense, c_ids/d.
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from typing import Callable, Dict, List

import torch

SOURCE = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(SOURCE, "tests", "python"))

import occgt  # noqa: E402
from occgt.torch import loftr_supervision  # noqa: E402
from supervision_test import make_batch, reference_supervision  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", default=os.path.join(os.path.dirname(SOURCE), "shared", "data"))
    ap.add_argument("--reps", type=int, default=25)
    args = ap.parse_args()
    torch.set_num_threads(1)
    ds = occgt.open_dataset(os.path.join(args.data, "sevenscenes"), "sevenscenes")
    scene = ds.scene(ds.scenes()[0])
    d0, K0, P0 = scene.load("000150")
    d1, K1, P1 = scene.load("000160")
    batch = make_batch([(d0, K0, P0, d1, K1, P1)])
    lo, hi = scene.min_depth_m, scene.max_depth_m

    def reference(dense: bool) -> Callable[[], object]:
        return lambda: reference_supervision(batch, fixes=False, dtype=torch.float32,
                                             with_status=False, dense=dense)

    cases: Dict[str, Callable[[], object]] = {
        "a": lambda: occgt.pair_ground_truth(d0, d1, K0, K1, P0, P1, min_depth_m=lo,
                                             max_depth_m=hi),
        "b": lambda: loftr_supervision(batch, "occ2net", dense_conf_matrix=False,
                                       min_depth_m=lo, max_depth_m=hi),
        "b_dense": lambda: loftr_supervision(batch, "occ2net", min_depth_m=lo, max_depth_m=hi),
        "c": reference(True),
        "c_ids": reference(False),
        "d_dense": lambda: loftr_supervision(batch),
        "d": lambda: loftr_supervision(batch, dense_conf_matrix=False),
    }
    names = list(cases)
    for f in cases.values():  # warm-up
        f()
    wall: Dict[str, List[float]] = {k: [] for k in names}
    cpu: Dict[str, List[float]] = {k: [] for k in names}
    for rep in range(args.reps):
        order = names[rep % len(names):] + names[: rep % len(names)]
        for k in order:
            t0, c0 = time.perf_counter(), time.process_time()
            cases[k]()
            wall[k].append(time.perf_counter() - t0)
            cpu[k].append(time.process_time() - c0)
    med_wall = {k: statistics.median(v) * 1e3 for k, v in wall.items()}
    med_cpu = {k: statistics.median(v) * 1e3 for k, v in cpu.items()}
    print(f"7-Scenes 000150/000160 at 640x480, {args.reps} repetitions, torch threads "
          f"{torch.get_num_threads()}, CPUs {sorted(os.sched_getaffinity(0))}")
    for k in names:
        print(f"  {k:8s} wall {med_wall[k]:8.3f} ms   cpu {med_cpu[k]:8.3f} ms")
    for num, den in (("c", "a"), ("c", "b"), ("c", "b_dense"), ("c", "d_dense"),
                     ("c_ids", "d")):
        print(f"  {num}/{den}: wall {med_wall[num] / med_wall[den]:6.2f}x   "
              f"cpu {med_cpu[num] / med_cpu[den]:6.2f}x")
    return 0


if __name__ == "__main__":
    sys.exit(main())
