"""`occgt build` and a second process, on the binary:
1. a build of a task whose lock another process holds (byte K of DIR/.tasks.lock, as a
   second `occgt build` of the same task into the same --out would hold it) stops at once
   with one line naming the folder and the task, exit 1, and writes no shard; a lock on
   another task's byte does not stop it (the tasks of an array job run together);
2. Ctrl-C (SIGINT) midway through the shards: one line saying how to resume, the process
   ends by the signal (exit 130 in a shell), and a re-run completes the split with the same
   files as an uninterrupted build."""
import fcntl
import glob
import os
import signal
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common  # noqa: E402
from crash_test import make_recipe  # noqa: E402


def main():
    root = common.scratch("build_lock")
    recipe = make_recipe(root)
    out = os.path.join(root, "locked")
    os.makedirs(out)
    fd = os.open(os.path.join(out, ".tasks.lock"), os.O_RDWR | os.O_CREAT, 0o644)
    fcntl.lockf(fd, fcntl.LOCK_EX | fcntl.LOCK_NB, 1, 0)  # task 0's byte
    r = common.occgt("build", recipe, "--out", out, check=False)
    assert r.returncode == 1, (r.returncode, r.stderr)
    lines = r.stderr.strip().splitlines()
    # One task: no "of task 0 of 1" (tasks are named only for a split into several).
    assert len(lines) == 1 and lines[0].startswith(f"occgt: error: {out}: another occgt build "
                                                   "is writing this folder"), lines
    assert not glob.glob(os.path.join(out, "*.tar")), "wrote shards while locked out"
    os.close(fd)  # released: the build runs
    ref = os.path.join(root, "ref")
    common.occgt("build", recipe, "--out", ref)
    # Another task's byte held: task 0 of 1 runs.
    other = os.path.join(root, "other_task")
    os.makedirs(other)
    fd = os.open(os.path.join(other, ".tasks.lock"), os.O_RDWR | os.O_CREAT, 0o644)
    fcntl.lockf(fd, fcntl.LOCK_EX | fcntl.LOCK_NB, 1, 1)
    common.occgt("build", recipe, "--out", other)
    os.close(fd)
    common.assert_same_outputs(ref, other)
    # A shard another task holds (a task of another --tasks count: task 2 of 3 and task 0 of
    # 2 both own shard 2): refused before any shard is written, one line naming the shard.
    shared = os.path.join(root, "shard_held")
    common.occgt("build", recipe, "--out", shared, "--stage", "select")
    fd = os.open(os.path.join(shared, ".shards.lock"), os.O_RDWR | os.O_CREAT, 0o644)
    fcntl.lockf(fd, fcntl.LOCK_EX | fcntl.LOCK_NB, 1, 2)  # shard 2's byte
    r = common.occgt("build", recipe, "--out", shared, "--stage", "write", "--tasks", "2",
                     "--task", "0", check=False)
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 1 and len(lines) == 1 and lines[0].startswith(
        f"occgt: error: {shared}: another occgt build is writing shard 2 of split "), lines
    assert not glob.glob(os.path.join(shared, "*.tar*")), "wrote a shard while one was held"
    common.occgt("build", recipe, "--out", shared, "--stage", "write", "--tasks", "2", "--task",
                 "1")  # shards 1: not held
    os.close(fd)
    common.occgt("build", recipe, "--out", shared)
    common.assert_same_outputs(ref, shared)

    # 2. SIGINT after the first published shard, then a re-run.
    out = os.path.join(root, "interrupted")
    common.occgt("build", recipe, "--out", out, "--dry-run")  # the synthetic data first
    p = subprocess.Popen([common.BINARY, "build", recipe, "--out", out, "--threads", "1"],
                         stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    try:
        while not glob.glob(os.path.join(out, "crash-*.tar")):
            assert p.poll() is None, f"build ended ({p.returncode}) before a shard appeared"
            time.sleep(0.005)
        p.send_signal(signal.SIGINT)
        _, err = p.communicate(timeout=60)
    finally:
        if p.poll() is None:
            p.kill()
    assert p.returncode == -signal.SIGINT, (p.returncode, err)
    assert "occgt: interrupted; re-run the same command to resume" in err, err
    assert not os.path.exists(os.path.join(out, "index.json")), "interrupted after the end"
    r = common.occgt("build", recipe, "--out", out)
    assert "wrote" in r.stdout, r.stdout
    n = common.assert_same_outputs(ref, out)
    print(f"locked out: one line, exit 1; other task's lock: built; SIGINT then re-run: {n} "
          "files identical to an uninterrupted build")


if __name__ == "__main__":
    main()
