#!/usr/bin/python3
"""The covisibility graph of one long synthetic room (docs/PERFORMANCE.md, "Covisibility graph").

    tests/bench/covis_bench.py [--binary build/apps/occgt] [--frames 2000] [--threads 2]
        [--scratch /tmp/occgt-covis-bench] [--pruning default|none] [--frame-stride S]

Generates `occgt synth --frames N --resolution 640x480` once (kept in the scratch folder),
then times `occgt covis` of a generic-format recipe over it: every pair of kept frames is a
candidate (no frame gap), pruned by camera distance 3 m, view angle 90 deg and the frustum
test (`--pruning none`: no pruning, every pair scored), scored both ways at score_stride 8.
Prints the wall time, candidates, pairs scored and pairs scored per second, and the peak RSS.
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time

SOURCE = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

RECIPE = """name: covis-bench
split: covis-bench
seed: 0
resolution: [640, 480]
dataset: {{format: generic, root: {root}, frame_stride: {stride}, min_valid_depth_fraction: 0.3}}
labels: {{preset: default}}
selection:
  pruning: {pruning}
  score_stride: 8
occupancy: {{enabled: false}}
sample: {{image: none, depth: true, labels: true, occupancy: false}}
"""
PRUNING = {"default": "{max_distance_m: 3.0, max_view_angle_deg: 90, frustum: true}",
           "none": "{max_distance_m: 0, max_view_angle_deg: 180, frustum: false}"}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--binary", default=os.path.join(SOURCE, "build", "apps", "occgt"))
    ap.add_argument("--frames", type=int, default=2000)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--scratch", default="/tmp/occgt-covis-bench")
    ap.add_argument("--pruning", choices=sorted(PRUNING), default="default")
    ap.add_argument("--frame-stride", type=int, default=1,
                    help="keep every n-th frame of the room (how the cost grows with frames)")
    args = ap.parse_args()
    data = os.path.join(args.scratch, f"synth{args.frames}")
    if not os.path.isdir(data):
        t0 = time.perf_counter()
        subprocess.run([args.binary, "synth", "--out", data, "--scenes", "1", "--frames",
                        str(args.frames), "--resolution", "640x480", "--seed", "0"], check=True,
                       stdout=subprocess.DEVNULL)
        print(f"synth: {time.perf_counter() - t0:.1f} s", file=sys.stderr)
    tag = f"{args.frames}-s{args.frame_stride}-{args.pruning}"
    recipe = os.path.join(args.scratch, f"covis{tag}.yaml")
    with open(recipe, "w") as f:
        f.write(RECIPE.format(root=data, pruning=PRUNING[args.pruning], stride=args.frame_stride))
    out = os.path.join(args.scratch, f"out{tag}")
    subprocess.run(["rm", "-rf", out], check=True)
    t0 = time.perf_counter()
    r = subprocess.run([args.binary, "covis", recipe, "--out", out, "--threads",
                        str(args.threads), "--json"], check=True, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    s = json.loads(r.stdout)
    rss = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
    print(f"frames {args.frames} / stride {args.frame_stride}, threads {args.threads}, "
          f"pruning {args.pruning}: "
          f"wall {wall:.1f} s, candidates {s['candidates']}, scored {s['pairs_scored']} "
          f"({s['pairs_scored'] / max(s['candidates'], 1):.3f}), "
          f"{s['pairs_scored'] / wall:.0f} pairs/s, peak RSS {rss:.0f} MB, drops {s['drops']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
