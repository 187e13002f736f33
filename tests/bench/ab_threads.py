#!/usr/bin/python3
"""Before/after of `occgt build --threads 1` and `--threads 2` on the same machine state
(docs/PERFORMANCE.md, "Threads and tasks"):

    tests/bench/ab_threads.py --base OLD/occgt [--new build/apps/occgt] [--reps 3]
                              [--one-core] RECIPE [RECIPE ...]

For each repetition and recipe, both binaries and both thread counts run interleaved (the
order flips every repetition) into a fresh output folder; prints each run (wall, CPU of the
process, 1-minute load) and per recipe and binary the medians and the median of the
per-repetition ratios t1 / t2. The load average and CPU pressure are printed before and
after; compare the binaries only within one run of this script. --one-core confines the
--threads 1 runs to one CPU (the baseline of a speed-up on 2 cores; e2e_bench.py one_cpu).
"""
import argparse
import os
import shutil
import statistics
import subprocess
import tempfile
import time

from e2e_bench import one_cpu, uptime  # as e2e_bench measures them

SOURCE = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def run(binary, recipe, threads, out, one_core=False):
    shutil.rmtree(out, ignore_errors=True)
    t0 = time.perf_counter()
    p = subprocess.Popen([binary, "build", "--json", recipe, "--out", out, "--threads", str(threads)],
                         stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                         preexec_fn=one_cpu(one_core))
    _, status, ru = os.wait4(p.pid, 0)
    wall = time.perf_counter() - t0
    if os.waitstatus_to_exitcode(status) != 0:
        raise SystemExit(f"ab_threads: {binary} build {recipe} failed:\n{p.stderr.read().decode()}")
    return wall, ru.ru_utime + ru.ru_stime


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--base", required=True, help="the 'before' occgt binary")
    ap.add_argument("--new", default=os.path.join(SOURCE, "build", "apps", "occgt"))
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--one-core", action="store_true",
                    help="run the --threads 1 builds on one CPU only")
    ap.add_argument("recipes", nargs="+")
    args = ap.parse_args()
    binaries = {"before": args.base, "after": args.new}
    out = tempfile.mkdtemp(prefix="occgt-ab-")
    res = {}
    print("load before:", uptime())
    for rep in range(args.reps):
        for recipe in args.recipes:
            for name in (("before", "after") if rep % 2 == 0 else ("after", "before")):
                for t in ((1, 2) if rep % 2 == 0 else (2, 1)):
                    w, c = run(binaries[name], recipe, t, os.path.join(out, "o"),
                               one_core=args.one_core and t == 1)
                    res.setdefault((recipe, name, t), []).append((w, c))
                    print(f"{rep} {os.path.basename(recipe)} {name} t{t}: {w:.2f} s wall, "
                          f"{c:.2f} s CPU, load {open('/proc/loadavg').read().split()[0]}",
                          flush=True)
    print("load after:", uptime())
    print("| recipe | build | t1 wall | t2 wall | t1/t2 | CPU t1 / t2 |")
    print("|---|---|---|---|---|---|")
    for recipe in args.recipes:
        for name in binaries:
            r1, r2 = res[(recipe, name, 1)], res[(recipe, name, 2)]
            ratios = [a[0] / b[0] for a, b in zip(r1, r2)]
            print(f"| {os.path.basename(recipe)} | {name} | "
                  f"{statistics.median(x[0] for x in r1):.2f} s | "
                  f"{statistics.median(x[0] for x in r2):.2f} s | "
                  f"{statistics.median(ratios):.2f} ({min(ratios):.2f}–{max(ratios):.2f}) | "
                  f"{statistics.median(x[1] for x in r1):.2f} / "
                  f"{statistics.median(x[1] for x in r2):.2f} s |")
    shutil.rmtree(out, ignore_errors=True)


if __name__ == "__main__":
    main()
