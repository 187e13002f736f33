"""Crash safety and invariance of `occgt build`, on the binary.

1. SIGKILL midway, then re-run: a build of a larger synthetic recipe (recipes/demo.yaml with
   3 rooms of 24 frames, 36 samples in 9 shards) is killed once right after the first scene's
   selection marker appears, right after the first shard's tar is renamed into place (its
   part record may not exist yet: the shard is then redone) and right after the first part
   record; each time a re-run completes the split, reuses what was complete, leaves no
   `*.tmp` file, and gives the same files, byte for byte, as an uninterrupted run.
2. `--threads 1` and `--threads 2` give the same files (the synthetic recipe and the real
   7-Scenes sample).
3. `--tasks 3` (select then write, every task one process), then `occgt merge` publishing
   index.json and pairs.jsonl, gives the same files as one process.
(build_demo_test covers the default thread count against --threads 1 and a 2-task split
whose last task publishes the indices.)
Under a sanitizer both recipes are built at half their width and height (common.py)."""
import glob
import json
import os
import signal
import subprocess
import sys
import time

import yaml

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common  # noqa: E402


def make_recipe(root):
    with open(os.path.join(common.SOURCE, "recipes", "demo.yaml")) as f:
        doc = yaml.safe_load(f)
    doc["name"] = doc["split"] = "crash"
    doc["dataset"]["synthetic"].update(scenes=3, frames=24)
    doc["shards"] = {"samples_per_shard": 4}
    common.half_size_when_sanitized(doc)
    path = os.path.join(root, "crash.yaml")
    with open(path, "w") as f:
        yaml.safe_dump(doc, f)
    return path


def build(recipe, out, *flags, env=None):
    r = common.occgt("build", "--json", recipe, "--out", out, *flags, env=env)
    return json.loads(r.stdout)


def kill_when(recipe, out, pattern, what):
    """Starts a build, SIGKILLs it as soon as a file matching pattern exists under out;
    returns the seconds it ran. Fails when the build finished first."""
    t0 = time.time()
    p = subprocess.Popen([common.BINARY, "build", "--json", recipe, "--out", out, "--threads", "2"],
                         stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        while not glob.glob(os.path.join(out, pattern)):
            assert p.poll() is None, f"build ended ({p.returncode}) before {what} appeared"
            time.sleep(0.005)
        p.send_signal(signal.SIGKILL)
    finally:
        p.wait()
    assert p.returncode == -signal.SIGKILL, p.returncode
    assert not os.path.exists(os.path.join(out, "index.json")), "killed after the end"
    return time.time() - t0


def main():
    t_start = time.time()
    root = common.scratch("crash")
    recipe = make_recipe(root)
    ref = os.path.join(root, "ref")
    s = build(recipe, ref, "--threads", "2")
    assert s["complete"] and s["samples"] == 36 and s["shards_planned"] == 9, s
    print(f"reference: {s['samples']} samples, {s['shards_planned']} shards, "
          f"{s['timings']['total_s']:.1f} s")

    # 1. Killed during selection, and during shard writing; then re-run.
    for name, pattern, what in (("select", "selection/*.json", "a selection marker"),
                                ("tar", "crash-*.tar", "a published tar"),
                                ("record", "parts/crash-0*.json", "a shard's part record")):
        out = os.path.join(root, "killed-" + name)
        # The synthetic data first, so that the kill does not land in its generation.
        build(recipe, out, "--dry-run")
        ran = kill_when(recipe, out, pattern, what)
        left = common.tmp_files(out)
        s = build(recipe, out, "--threads", "2")
        assert s["complete"], s
        if name == "select":
            assert s["scenes_reused"] >= 1, s
        else:
            assert s["scenes_reused"] == 3, s
        if name == "record":
            assert s["shards_skipped_complete"] >= 1, s
        assert not common.tmp_files(out), common.tmp_files(out)
        n = common.assert_same_outputs(ref, out)
        print(f"killed after {ran:.2f} s at {what} ({len(left)} .tmp left), re-run reused "
              f"{s['scenes_reused']} scenes and {s['shards_skipped_complete']} shards: "
              f"{n} files identical")

    # 2. One thread against two: the synthetic recipe and the real 7-Scenes sample.
    out = os.path.join(root, "threads1")
    build(recipe, out, "--threads", "1")
    n = common.assert_same_outputs(ref, out)
    common.shared("sevenscenes")
    env = dict(os.environ, OCCGT_SHARED_DATA=common.SHARED)
    seven = os.path.join(common.SOURCE, "recipes", "sevenscenes-sample.yaml")
    if common.SANITIZER:
        with open(seven) as f:
            doc = yaml.safe_load(f)
        common.half_size_when_sanitized(doc)
        seven = os.path.join(root, "sevenscenes-half.yaml")
        with open(seven, "w") as f:
            yaml.safe_dump(doc, f)
    for threads in ("1", "2"):
        build(seven, os.path.join(root, "seven-t" + threads), "--threads", threads, env=env)
    n7 = common.assert_same_outputs(os.path.join(root, "seven-t2"), os.path.join(root, "seven-t1"))
    print(f"--threads 1 vs 2: {n} files (synthetic), {n7} files (7-Scenes) identical")

    # 3. Three tasks, each stage a process per task, then occgt merge publishes the indices.
    out = os.path.join(root, "tasks3")
    for stage in ("select", "write"):
        for task in ("2", "0", "1"):
            s = build(recipe, out, "--tasks", "3", "--task", task, "--stage", stage)
            assert s["task"] == int(task) and s["tasks"] == 3, s
    for name in ("index.json", "pairs.jsonl"):
        os.remove(os.path.join(out, name))
    r = common.occgt("merge", out)
    assert "merged split crash: 9 shards, 36 samples" in r.stdout, r.stdout
    n = common.assert_same_outputs(ref, out)
    print(f"--tasks 3 + occgt merge: {n} files identical")
    print(f"crash: 1 passed, 0 failed ({time.time() - t_start:.1f} s)")


if __name__ == "__main__":
    main()
