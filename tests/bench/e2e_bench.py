#!/usr/bin/python3
"""End-to-end benchmark of `occgt build` (docs/PERFORMANCE.md, section "Scale").

    tests/bench/e2e_bench.py [--build build] [--reps 5] [--scratch /tmp/occgt-e2e-bench]
                             [--frames 250,1000] [--skip-speedup] [--skip-large]
                             [--skip-scene] [--json F]

1. speed-up: `occgt build` on the samples (recipes/sevenscenes-sample.yaml,
   tartanair-sample.yaml, demo.yaml with its synthetic data generated beforehand) in a
   fresh output folder, `--reps` times each of: --threads 1 confined to one CPU ("1 core",
   sched_setaffinity; the baseline of the speed-up on 2 cores), --threads 1 on the whole
   machine ("t1") and --threads 2 ("t2"), in a rotating order; wall time, CPU time and peak
   RSS of each process (os.wait4), the stage times of its summary, bytes per sample (shards /
   samples). Reports medians and the median ratios 1 core / t2 and t1 / t2; also
   the same build as 2 tasks of 1 thread running at once (the Slurm layout on one machine),
   and the machine's own 2-core ceiling for the build: 2 x (1 core wall) / (wall of two
   independent one-core runs of it at once, one per CPU).
   Then the same on larger bench variants of the two sample recipes (not shipped; written
   into the scratch folder, same sample data): frame_stride 1 and a higher quota, 7-Scenes
   also overlap [0.1, 1.0] (its 50 frames give 17 pairs in [0.4, 0.9]), so that the run is
   long enough for the serial parts (process start, selection, the last shard's
   publication, the index) not to dominate t1 / t2 (--skip-large leaves them out).
2. one long scene: `occgt synth` rooms of N frames (--frames, 640x480) read by a recipe
   with recipes/scannet-train.yaml's selection (max_frame_gap 60, score_stride 10, overlap
   [0.4, 0.8], jpg, no depth, pair OctoMap occupancy) and a quota of 40 pairs; built with
   --threads 2 at --depth-cache-mb 512 and 64 (peak RSS against N) and once with --threads 1
   on one CPU
   (per-core rates of both stages, the inputs of the projection).
3. projection: hours on 64 cores for the ScanNet train split (from (2)'s per-core rates)
   and TartanAir (from tartanair-sample's one-core runs); see projection().
The machine load (`uptime`) is printed before and after; other processes inflate wall times.
"""
import argparse
import json
import os
import re
import shutil
import statistics
import subprocess
import sys
import time

import yaml

SOURCE = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def uptime():
    """`uptime`, plus the CPU pressure (PSI: share of time some runnable task waited for a CPU)."""
    text = subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()
    try:
        with open("/proc/pressure/cpu") as f:
            text += "; cpu pressure " + f.readline().strip()
    except OSError:
        pass
    return text


def one_cpu(confine=True):
    """preexec_fn: the child may run on one CPU only (the lowest of this process's set), as a
    Slurm task with --cpus-per-task=1 does; its helper threads share that CPU. With
    confine=False a no-op, so that every timed run is started the same way (fork + exec:
    subprocess uses vfork only without a preexec_fn)."""
    cpu = min(os.sched_getaffinity(0))
    return (lambda: os.sched_setaffinity(0, {cpu})) if confine else (lambda: None)


def timed(cmd, env=None, one_core=False):
    """Runs cmd with os.wait4 for its own rusage: (stdout text, wall s, cpu s, max RSS MB).
    one_core: the process and all its threads are confined to one CPU (sched_setaffinity)."""
    t0 = time.perf_counter()
    out_path = os.path.join(ARGS.scratch, ".stdout")
    err_path = os.path.join(ARGS.scratch, ".stderr")
    with open(out_path, "w") as out, open(err_path, "w") as err:
        p = subprocess.Popen(cmd, stdout=out, stderr=err, env=env,
                             preexec_fn=one_cpu(one_core))
        _, status, ru = os.wait4(p.pid, 0)
    wall = time.perf_counter() - t0
    p.returncode = os.waitstatus_to_exitcode(status)
    if p.returncode != 0:
        sys.exit(f"e2e_bench: {' '.join(cmd)} failed ({p.returncode}):\n{open(err_path).read()}")
    return open(out_path).read(), wall, ru.ru_utime + ru.ru_stime, ru.ru_maxrss / 1024.0


def pair_of_one_core_runs(recipe, outs, seed_data=None):
    """The machine's own 2-core ceiling for this build: the same `--threads 1` build twice at
    once, each process confined to its own CPU (the two lowest of this process's set), into
    two fresh folders. Returns (wall s of the pair = the later of the two, [cpu s of each]).
    2 x (one-core wall) / (pair wall) is the throughput two cores give two independent jobs,
    the most any threading of one job can reach on this machine at that moment (shared
    caches, memory bandwidth, the host's scheduling of the two vCPUs)."""
    cpus = sorted(os.sched_getaffinity(0))[:2]
    procs = []
    for out in outs:
        shutil.rmtree(out, ignore_errors=True)
        if seed_data:
            os.makedirs(out)
            shutil.copytree(seed_data, os.path.join(out, "data"))
    t0 = time.perf_counter()
    for out, cpu in zip(outs, cpus):
        procs.append(subprocess.Popen(
            [OCCGT, "build", "--json", recipe, "--out", out, "--threads", "1"],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
            preexec_fn=(lambda c=cpu: os.sched_setaffinity(0, {c}))))
    cpu_s = []
    for p in procs:
        _, status, ru = os.wait4(p.pid, 0)
        if os.waitstatus_to_exitcode(status) != 0:
            sys.exit(f"e2e_bench: pair of one-core builds of {recipe} failed")
        cpu_s.append(ru.ru_utime + ru.ru_stime)
    return time.perf_counter() - t0, cpu_s


def shard_bytes(out):
    with open(os.path.join(out, "index.json")) as f:
        return sum(s["filesize"] for s in json.load(f)["shardlist"])


def build(recipe, out, threads, extra=(), seed_data=None, one_core=False):
    shutil.rmtree(out, ignore_errors=True)
    if seed_data:
        os.makedirs(out)
        shutil.copytree(seed_data, os.path.join(out, "data"))
    text, wall, cpu, rss = timed([OCCGT, "build", "--json", recipe, "--out", out, "--threads", str(threads),
                                  *extra], one_core=one_core)
    s = json.loads(text)
    return {"wall_s": wall, "cpu_s": cpu, "rss_mb": rss, "select_s": s["timings"]["select_s"],
            "write_s": s["timings"]["write_s"], "samples": s["samples"],
            "frames": s["counts"]["frames_kept"], "scored": s["counts"]["scored"],
            "candidates": s["counts"]["candidates"], "bytes": shard_bytes(out)}


def build_two_tasks(recipe, out, seed_data=None):
    """--tasks 2, one thread each, both tasks at once: select, then write (the last write
    task publishes the indices). Returns the wall seconds of the whole."""
    shutil.rmtree(out, ignore_errors=True)
    if seed_data:
        os.makedirs(out)
        shutil.copytree(seed_data, os.path.join(out, "data"))
    t0 = time.perf_counter()
    for stage in ("select", "write"):
        procs = [subprocess.Popen([OCCGT, "build", "--json", recipe, "--out", out, "--threads", "1",
                                   "--tasks", "2", "--task", str(k), "--stage", stage],
                                  stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
                 for k in (0, 1)]
        for p in procs:
            _, err = p.communicate()
            if p.returncode != 0:
                sys.exit(f"e2e_bench: two-task {stage} failed:\n{err.decode()}")
    return time.perf_counter() - t0


def med(rows, key):
    return statistics.median(r[key] for r in rows)


def large_recipe(name, changes):
    """A bench variant of recipes/NAME.yaml in the scratch folder: the dataset root made
    absolute (${VAR:-default} expanded as the recipe loader does), `changes` (section ->
    {key: value}) applied, name and split suffixed "-large"."""
    with open(os.path.join(SOURCE, "recipes", name + ".yaml")) as f:
        doc = yaml.safe_load(f)
    root = re.sub(r"\$\{(\w+):-([^}]*)\}", lambda m: os.environ.get(m.group(1), m.group(2)),
                  doc["dataset"]["root"])
    doc["dataset"]["root"] = os.path.normpath(os.path.join(SOURCE, "recipes", root))
    for section, values in changes.items():
        doc[section].update(values)
    doc["name"] = doc["split"] = name + "-large"
    path = os.path.join(ARGS.scratch, name + "-large.yaml")
    with open(path, "w") as f:
        yaml.safe_dump(doc, f)
    return path


def speedup(results):
    recipes = [("sevenscenes-sample", os.path.join(SOURCE, "recipes", "sevenscenes-sample.yaml")),
               ("tartanair-sample", os.path.join(SOURCE, "recipes", "tartanair-sample.yaml")),
               ("demo", os.path.join(SOURCE, "recipes", "demo.yaml"))]
    demo_data = os.path.join(ARGS.scratch, "demo-data")
    if not os.path.exists(os.path.join(demo_data, "data", ".complete")):
        timed([OCCGT, "build", "--json", recipes[2][1], "--out", demo_data, "--dry-run"])
    print("\n## speed-up on 2 cores: --threads 1 on one CPU, --threads 1 and --threads 2 on both "
          "(fresh output folder each run)")
    speedup_table(results, recipes, demo_data)
    if not ARGS.skip_large:
        large = [("sevenscenes-sample-large (bench variant: stride 1, overlap [0.1, 1], quota 48)",
                  large_recipe("sevenscenes-sample",
                               {"dataset": {"frame_stride": 1},
                                "selection": {"overlap": [0.1, 1.0], "quota_per_scene": 48}})),
                 ("tartanair-sample-large (bench variant: quota 40)",
                  large_recipe("tartanair-sample", {"selection": {"quota_per_scene": 40}}))]
        print("\n## speed-up on larger bench variants of the sample recipes (same data, "
              "more pairs; not shipped recipes)")
        speedup_table(results, large, demo_data)


def speedup_table(results, recipes, demo_data):
    """Four runs per repetition, in an order that rotates: "1 core" (--threads 1 confined to
    one CPU: the baseline of the speed-up on 2 cores), "t1" (--threads 1 on the whole machine:
    its fsync and digest helper threads, and the kernel's writeback, may use the other CPU),
    "t2" (--threads 2) and "pair" (two one-core runs at once, one per CPU: the ceiling
    2 x 1 core / pair, see pair_of_one_core_runs). Ratios are per repetition, then the
    median."""
    print("| recipe | samples | 1 core wall | t1 wall | t2 wall "
          "| speed-up 1 core / t2 (median of reps) | ceiling 2 x 1 core / pair | t1 / t2 "
          "| t1 select / write | t2 select / write | 2 tasks x 1 thread wall (t1 / that) "
          "| CPU 1 core / t1 / t2 | peak RSS t1 / t2 | bytes/sample |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    conditions = [("c1", 1, True), ("t1", 1, False), ("t2", 2, False)]
    for name, recipe in recipes:
        rows = {c: [] for c, _, _ in conditions}
        seed = os.path.join(demo_data, "data") if name == "demo" else None
        folder = name.split(" ")[0]
        pairs = []  # (wall, [cpu, cpu]) of the pair of one-core runs, one per repetition
        actions = conditions + [("pair", 1, True)]
        for rep in range(ARGS.reps):
            k = rep % len(actions)
            for c, threads, one_core in actions[k:] + actions[:k]:
                if c == "pair":
                    pairs.append(pair_of_one_core_runs(
                        recipe, [os.path.join(ARGS.scratch, f"{folder}-pair{i}") for i in (0, 1)],
                        seed))
                    continue
                rows[c].append(build(recipe, os.path.join(ARGS.scratch, f"{folder}-{c}"), threads,
                                     seed_data=seed, one_core=one_core))
        two = [build_two_tasks(recipe, os.path.join(ARGS.scratch, f"{folder}-p2"), seed)
               for _ in range(ARGS.reps)]
        c1, r1, r2 = rows["c1"], rows["t1"], rows["t2"]
        core_ratios = [a["wall_s"] / b["wall_s"] for a, b in zip(c1, r2)]
        ceilings = [2 * a["wall_s"] / w for a, (w, _) in zip(c1, pairs)]
        ratios = [a["wall_s"] / b["wall_s"] for a, b in zip(r1, r2)]
        results["speedup"][name] = {"one_core": c1, "t1": r1, "t2": r2,
                                    "ratios_one_core": core_ratios, "ratios": ratios,
                                    "pair_wall_s": [w for w, _ in pairs],
                                    "pair_cpu_s": [c for _, c in pairs], "ceilings": ceilings,
                                    "tasks2_wall_s": two}

        def rng(v):
            return f"{statistics.median(v):.2f} ({min(v):.2f}–{max(v):.2f})"

        print(f"| {name} | {r1[0]['samples']} | {med(c1, 'wall_s'):.2f} s "
              f"| {med(r1, 'wall_s'):.2f} s | {med(r2, 'wall_s'):.2f} s "
              f"| {rng(core_ratios)} | {rng(ceilings)} | {rng(ratios)} "
              f"| {med(r1, 'select_s'):.2f} / {med(r1, 'write_s'):.2f} s "
              f"| {med(r2, 'select_s'):.2f} / {med(r2, 'write_s'):.2f} s "
              f"| {statistics.median(two):.2f} s ({med(r1, 'wall_s') / statistics.median(two):.2f}) "
              f"| {med(c1, 'cpu_s'):.2f} / {med(r1, 'cpu_s'):.2f} / {med(r2, 'cpu_s'):.2f} s "
              f"| {med(r1, 'rss_mb'):.0f} / {med(r2, 'rss_mb'):.0f} MB "
              f"| {r1[0]['bytes'] / r1[0]['samples'] / 1e6:.2f} MB |", flush=True)
    print(f"load after the table: {uptime()}")


def scene_recipe(data, frames):
    with open(os.path.join(SOURCE, "recipes", "scannet-train.yaml")) as f:
        doc = yaml.safe_load(f)
    doc["name"] = doc["split"] = f"long{frames}"
    doc["dataset"] = {"format": "generic", "root": data, "frame_stride": 1,
                      "min_valid_depth_fraction": 0.3}
    doc["selection"]["quota_per_scene"] = 40
    doc.pop("loftr_export", None)
    doc["shards"] = {"samples_per_shard": 10}
    path = os.path.join(ARGS.scratch, f"long{frames}.yaml")
    with open(path, "w") as f:
        yaml.safe_dump(doc, f)
    return path


def long_scene(results):
    print("\n## one long scene (640x480 synthetic room, ScanNet-train selection, quota 40)")
    print("| frames | threads | depth cache | wall | select | write | candidates | scored "
          "| peak RSS |")
    print("|---|---|---|---|---|---|---|---|---|")
    for frames in ARGS.frames:
        data = os.path.join(ARGS.scratch, f"synth{frames}")
        if not os.path.exists(os.path.join(data, "dataset.json")):
            shutil.rmtree(data, ignore_errors=True)
            timed([OCCGT, "synth", "--out", data, "--scenes", "1", "--frames", str(frames),
                   "--resolution", "640x480"])
        recipe = scene_recipe(data, frames)
        for threads, cache in ((2, 512), (2, 64), (1, 512)):
            r = build(recipe, os.path.join(ARGS.scratch, f"long{frames}-out"), threads,
                      extra=("--depth-cache-mb", str(cache)), one_core=threads == 1)
            r.update(frames_in=frames, threads=threads, cache_mb=cache)
            results["long_scene"].append(r)
            print(f"| {frames} | {threads} | {cache} MB | {r['wall_s']:.1f} s | {r['select_s']:.1f} s "
                  f"| {r['write_s']:.1f} s | {r['candidates']} | {r['scored']} | {r['rss_mb']:.0f} MB |")


def projection(results):
    """Core-hours of both stages at full size from per-core (one-core --threads 1) medians: ScanNet
    from the long synthetic scene (its recipe is scannet-train's selection), TartanAir from
    recipes/tartanair-sample.yaml. Select scales with kept frames (at the measured candidate
    density), write with samples; tasks are independent, so cores divide the time."""
    cores = 64
    for basis in ("wall", "cpu"):
        projection_on(results, cores, basis)


def projection_on(results, cores, basis):
    """basis "wall": stage wall times of the one-core run (pessimistic on a loaded
    machine); "cpu": the same scaled by the run's CPU time / wall time (the core share the
    process really got), an estimate for idle cores."""
    rates = {}

    def scale(r):
        return r["cpu_s"] / r["wall_s"] if basis == "cpu" else 1.0

    rows = [r for r in results["long_scene"] if r["threads"] == 1]
    if rows:
        r = max(rows, key=lambda x: x["frames_in"])
        f = scale(r)
        rates["scannet"] = (f * r["select_s"] / r["frames"], f * r["write_s"] / r["samples"],
                            r["bytes"] / r["samples"], f"long scene, {r['frames_in']} frames")
    t = results["speedup"].get("tartanair-sample")
    if t:
        rows1 = t.get("one_core") or t["t1"]  # saved results of older runs have no one-core rows
        f = statistics.median(scale(r) for r in rows1)
        rates["tartanair"] = (f * med(rows1, "select_s") / rows1[0]["frames"],
                              f * med(rows1, "write_s") / rows1[0]["samples"],
                              rows1[0]["bytes"] / rows1[0]["samples"], "tartanair-sample")
    if not rates:
        return
    print(f"\n## projection on {cores} cores (per-core rates from one-core --threads 1 runs, {basis} basis)")
    for k, (sel, wr, b, src) in rates.items():
        print(f"{k} ({src}): select {sel * 1e3:.1f} core-ms per kept frame, write "
              f"{wr * 1e3:.0f} core-ms per sample ({1 / wr:.2f} samples/s per core), "
              f"{b / 1e6:.2f} MB per sample")
    frames_scannet_train = 2.5e6 * 1201 / 1513 / 5  # frames of 1201 of 1513 scans, stride 5
    cases = [
        ("scannet", "ScanNet train, recipe (stride 5, quota 2000/scene)", frames_scannet_train,
         1201 * 2000),
        ("scannet", "ScanNet train, 230 M samples written", frames_scannet_train, 230e6),
        ("tartanair", "TartanAir, 370 traj. x 2000 samples", 300e3, 370 * 2000),
    ]
    print("| case | kept frames | samples | select | write | total | shard bytes |")
    print("|---|---|---|---|---|---|---|")
    results.setdefault("projection", {})[basis] = []
    for key, name, frames, samples in cases:
        if key not in rates:
            continue
        sel, wr, b, _ = rates[key]
        sel_h = frames * sel / cores / 3600
        wr_h = samples * wr / cores / 3600
        results["projection"][basis].append({"case": name, "frames": frames, "samples": samples,
                                      "select_h": sel_h, "write_h": wr_h, "bytes": samples * b})
        print(f"| {name} | {frames:.3g} | {samples:.3g} | {sel_h:.2f} h | {wr_h:.1f} h "
              f"| {sel_h + wr_h:.1f} h | {samples * b / 1e12:.2f} TB |")


def main():
    global ARGS, OCCGT
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build", default=os.path.join(SOURCE, "build"))
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--scratch", default="/tmp/occgt-e2e-bench")
    ap.add_argument("--frames", default="250,1000")
    ap.add_argument("--skip-speedup", action="store_true")
    ap.add_argument("--skip-large", action="store_true")
    ap.add_argument("--skip-scene", action="store_true")
    ap.add_argument("--json", default="")
    ap.add_argument("--from-json", nargs="+", default=[],
                    help="only print the projection from saved --json files (merged)")
    ARGS = ap.parse_args()
    if ARGS.from_json:
        results = {"speedup": {}, "long_scene": []}
        for path in ARGS.from_json:
            with open(path) as f:
                doc = json.load(f)
            results["speedup"].update(doc["speedup"])
            results["long_scene"] += doc["long_scene"]
        projection(results)
        return
    ARGS.frames = [int(x) for x in ARGS.frames.split(",") if x]
    OCCGT = os.path.join(ARGS.build, "apps", "occgt")
    os.makedirs(ARGS.scratch, exist_ok=True)
    results = {"uptime_before": uptime(), "speedup": {}, "long_scene": [], "nproc": os.cpu_count()}
    print(f"# occgt e2e bench, {time.strftime('%Y-%m-%d %H:%M')}, {os.cpu_count()} cores")
    print(f"load before: {results['uptime_before']}")
    if not ARGS.skip_speedup:
        speedup(results)
    if not ARGS.skip_scene:
        long_scene(results)
    projection(results)
    results["uptime_after"] = uptime()
    print(f"\nload after: {results['uptime_after']}")
    if ARGS.json:
        with open(ARGS.json, "w") as f:
            json.dump(results, f, indent=1)


ARGS = None
OCCGT = ""

if __name__ == "__main__":
    main()
