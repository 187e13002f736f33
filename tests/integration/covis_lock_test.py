"""`occgt covis` and `occgt tuples` hold a per-task lock, as `occgt build` does
(libgt/pipeline/build.h AcquireTaskLock, docs/CLI.md "covis and tuples"):

1. covis of task K whose byte of DIR/.covis.lock another process holds (as a second
   `occgt covis` of the same task into the same --out would hold it) stops at once with one
   line naming the folder and the task, exit 1, and writes no graph; a different task runs
   meanwhile; and the byte another build task holds in DIR/.tasks.lock does not stop covis.
2. Real processes: while one `occgt covis` of task 0 runs (held waiting on the folder lock,
   DIR/.lock, that the test holds), a second one of task 0 into the same folder is refused
   with that line, one of task 1 takes its own byte and runs; both finish once released.
3. tuples while DIR/.tuples.lock is held: refused, no tuples.jsonl written; released: runs.
"""
import fcntl
import glob
import os
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common  # noqa: E402

RECIPE = """name: covis-lock-test
split: cl
seed: 0
resolution: [%d, %d]
dataset:
  format: synthetic
  synthetic: {scenes: 2, frames: %d, width: %d, height: %d, seed: 4}
  frame_stride: 1
  min_valid_depth_fraction: 0.3
labels: {preset: default}
selection:
  pruning: {max_distance_m: 4.0, max_view_angle_deg: 120, frustum: true}
  score_stride: 4
  views: 3
  tuples: {edge_threshold: 0.2, quota_per_scene: 2}
occupancy: {enabled: false}
"""


def hold(path, slot):
    fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
    fcntl.lockf(fd, fcntl.LOCK_EX | fcntl.LOCK_NB, 1, slot)
    return fd


def refused(r, out, command, task, tasks):
    lines = r.stderr.strip().splitlines()
    of_task = f" of task {task}" if tasks > 1 else ""
    want = f"occgt: error: {out}: another occgt {command}{of_task} is writing this folder now"
    assert r.returncode == 1 and len(lines) == 1 and lines[0].startswith(want), (r.returncode, lines)


def wait_for_byte(lock, slot, process):
    """Returns once another process holds byte `slot` of `lock` (fails if `process` ends)."""
    deadline = time.time() + 120
    while True:
        assert process.poll() is None, f"covis ended ({process.returncode}) early: {process.stderr.read()}"
        assert time.time() < deadline, f"byte {slot} of {lock} never taken"
        if os.path.exists(lock):
            fd = os.open(lock, os.O_RDWR)
            try:
                fcntl.lockf(fd, fcntl.LOCK_EX | fcntl.LOCK_NB, 1, slot)
                fcntl.lockf(fd, fcntl.LOCK_UN, 1, slot)
            except OSError:
                return
            finally:
                os.close(fd)
        time.sleep(0.01)


def main():
    root = common.scratch("covis_lock")
    recipe = os.path.join(root, "recipe.yaml")
    with open(recipe, "w") as f:
        f.write(RECIPE % (96, 72, 10, 96, 72))
    data = os.path.join(root, "data")

    # 1. A held byte of DIR/.covis.lock.
    out = os.path.join(root, "held")
    os.makedirs(out)
    fd = hold(os.path.join(out, ".covis.lock"), 0)
    r = common.occgt("covis", recipe, "--out", out, "--task", 0, "--tasks", 2, "--root", data,
                     check=False)
    refused(r, out, "covis", 0, 2)
    assert not glob.glob(os.path.join(out, "covisibility", "*.npz")), "wrote a graph while locked out"
    common.occgt("covis", recipe, "--out", out, "--task", 1, "--tasks", 2, "--root", data)
    assert len(glob.glob(os.path.join(out, "covisibility", "*.npz"))) == 1, "task 1 wrote no graph"
    os.close(fd)
    # A build's lock of the same task does not stop covis (they write different files).
    fd = hold(os.path.join(out, ".tasks.lock"), 0)
    common.occgt("covis", recipe, "--out", out, "--task", 0, "--tasks", 2, "--root", data)
    os.close(fd)
    assert len(glob.glob(os.path.join(out, "covisibility", "*.npz"))) == 2

    # 3. tuples.
    fd = hold(os.path.join(out, ".tuples.lock"), 0)
    r = common.occgt("tuples", recipe, "--out", out, "--root", data, check=False)
    refused(r, out, "tuples", 0, 1)
    assert not os.path.exists(os.path.join(out, "tuples.jsonl")), "tuples written while locked out"
    os.close(fd)
    common.occgt("tuples", recipe, "--out", out, "--root", data)
    assert os.path.exists(os.path.join(out, "tuples.jsonl"))

    # 2. Real processes. The test holds DIR/.lock (the folder lock under which covis generates
    # a synthetic dataset): a covis takes its task byte, then waits there, so it is running
    # for as long as the test wants.
    out = os.path.join(root, "race")
    os.makedirs(out)
    folder = os.open(os.path.join(out, ".lock"), os.O_RDWR | os.O_CREAT, 0o644)
    fcntl.flock(folder, fcntl.LOCK_EX)
    cmd = [common.BINARY, "covis", recipe, "--out", out, "--tasks", "2"]
    first = subprocess.Popen(cmd + ["--task", "0"], stdout=subprocess.DEVNULL,
                             stderr=subprocess.PIPE, text=True)
    other = None
    try:
        wait_for_byte(os.path.join(out, ".covis.lock"), 0, first)
        r = common.occgt("covis", recipe, "--out", out, "--task", 0, "--tasks", 2, check=False)
        refused(r, out, "covis", 0, 2)
        assert first.poll() is None, "the first covis ended while the folder lock was held"
        other = subprocess.Popen(cmd + ["--task", "1"], stdout=subprocess.DEVNULL,
                                 stderr=subprocess.PIPE, text=True)
        wait_for_byte(os.path.join(out, ".covis.lock"), 1, other)  # task 1 runs meanwhile
        assert first.poll() is None
        fcntl.flock(folder, fcntl.LOCK_UN)
        for p in (first, other):
            _, err = p.communicate(timeout=600)
            assert p.returncode == 0, err
    finally:
        for p in (first, other):
            if p is not None and p.poll() is None:
                p.kill()
        os.close(folder)
    assert len(glob.glob(os.path.join(out, "covisibility", "*.npz"))) == 2
    print("covis_lock: OK")


if __name__ == "__main__":
    main()
