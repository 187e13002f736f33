"""occgt build on a real single-node Slurm cluster (Debian's slurmctld, slurmd, munge),
the way docs/SCALE.md runs it: scripts/slurm/submit.sh submits a 4-task select array, a
4-task write array (afterok) and a merge job (afterok, --kill-on-invalid-dep=yes); the
tasks take their layout from SLURM_ARRAY_TASK_*. Every file of the result (shards,
index.json, pairs.jsonl, part records, selections, recipe.json, LoFTR export, generated
data; summary.json on its run-independent keys) must equal a one-process run byte for byte.
A recipe whose select tasks fail gets its write array and merge job cancelled.

The cluster is started by scripts/slurm/local_cluster.sh (which installs the Debian packages
when missing) in a scratch state folder on free ports, and always stopped in `finally` by
the PIDs in its pid files. Needs root; skipped with a message only when not root."""
import os
import re
import socket
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common  # noqa: E402

PACKAGES = ("slurmctld", "slurmd", "slurm-client", "munge")
NTASKS = 4
RECIPES = (("demo", "demo.yaml", None),
           ("sevenscenes", "sevenscenes-sample.yaml", "sevenscenes"),
           ("tartanair", "tartanair-sample.yaml", "tartanair/hospital_sample"))
TIMEOUT_S = 240  # for all jobs of all recipes


def installed(package):
    r = subprocess.run(["dpkg-query", "-W", "-f=${Status}", package], capture_output=True, text=True)
    return r.returncode == 0 and "install ok installed" in r.stdout


def free_port_pair():
    """A port p with p and p + 1 free on localhost (slurmctld, slurmd)."""
    for p in range(16817, 17817, 2):
        try:
            for q in (p, p + 1):
                with socket.socket() as s:
                    s.bind(("127.0.0.1", q))
            return p
        except OSError:
            continue
    raise AssertionError("no free port pair in 16817-17817")


def read_pid(path):
    try:
        with open(path) as f:
            return int(f.read().strip())
    except (OSError, ValueError):
        return None


def alive(pid):
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return True


def logs_of(out):
    folder = os.path.join(out, "slurm-logs")
    text = ""
    for name in sorted(os.listdir(folder)) if os.path.isdir(folder) else []:
        with open(os.path.join(folder, name)) as f:
            text += f"--- {name}\n{f.read()}"
    return text


def job_states(env, job_id):
    """{JobId_ArrayTaskId: JobState} of a job (one entry per array task)."""
    r = subprocess.run(["scontrol", "-o", "show", "job", job_id], capture_output=True, text=True,
                       env=env)
    states = {}
    for line in r.stdout.splitlines():
        task = re.search(r"ArrayTaskId=(\S+)", line)
        state = re.search(r"JobState=(\S+)", line)
        states[f"{job_id}_{task.group(1) if task else '-'}"] = state.group(1) if state else "?"
    return states


def main():
    t_start = time.time()
    if os.geteuid() != 0:
        missing = [p for p in PACKAGES if not installed(p)]
        print("SKIP: slurm_test needs root to start slurmd/slurmctld"
              + (f" and to install {' '.join(missing)}" if missing else "")
              + "; run ctest as root (CI does)")
        return
    root = common.scratch("slurm")
    state = os.path.join(root, "cluster")
    script_dir = os.path.join(common.SOURCE, "scripts", "slurm")
    env = dict(os.environ, OCCGT_SLURM_PORT=str(free_port_pair()),
               SLURM_CONF=os.path.join(state, "slurm.conf"), OCCGT_BIN=common.BINARY,
               OCCGT_SHARED_DATA=common.SHARED, OCCGT_CPUS_PER_TASK="1")
    env.pop("SLURM_ARRAY_TASK_ID", None)  # the reference runs are one process
    jobs = []
    pidfiles = [os.path.join(state, n) for n in ("slurmctld.pid", "slurmd.pid", "munged.pid")]
    try:
        r = subprocess.run(["bash", os.path.join(script_dir, "local_cluster.sh"), "start", state],
                           stdin=subprocess.DEVNULL, capture_output=True, text=True, env=env,
                           timeout=900)
        assert r.returncode == 0, f"local_cluster.sh start failed ({r.returncode}):\n{r.stderr}"
        t_up = time.time()
        print(f"cluster up in {t_up - t_start:.1f} s (installs the packages when missing)")

        # Submit every recipe's three jobs, then run the one-process references meanwhile.
        outs = {}
        for name, recipe_file, data_rel in RECIPES:
            if data_rel:
                common.shared(data_rel)  # fails loudly when the real sample is missing
            out = os.path.join(root, name, "slurm")
            recipe = os.path.join(common.SOURCE, "recipes", recipe_file)
            r = subprocess.run(["bash", os.path.join(script_dir, "submit.sh"), recipe, out,
                                str(NTASKS)], stdin=subprocess.DEVNULL, capture_output=True,
                               text=True, env=env)
            assert r.returncode == 0, f"submit.sh {recipe_file} failed:\n{r.stderr}"
            m = re.fullmatch(r"select=(\d+) write=(\d+) merge=(\d+)\n", r.stdout)
            assert m, r.stdout
            jobs += list(m.groups())
            outs[name] = (recipe, out, m.groups())
        # A failing select array (dataset root missing): write and merge must be cancelled.
        bad_recipe = os.path.join(root, "bad.yaml")
        with open(os.path.join(common.SOURCE, "recipes", "demo.yaml")) as f:
            text = re.sub(r"\n  synthetic: [^\n]*", "", f.read()).replace(
                "format: synthetic", "format: sevenscenes\n  root: /nonexistent")
        with open(bad_recipe, "w") as f:
            f.write(text)
        bad_out = os.path.join(root, "bad", "slurm")
        r = subprocess.run(["bash", os.path.join(script_dir, "submit.sh"), bad_recipe, bad_out,
                            str(NTASKS)], stdin=subprocess.DEVNULL, capture_output=True,
                           text=True, env=env)
        assert r.returncode == 0, f"submit.sh bad.yaml failed:\n{r.stderr}"
        bad_ids = re.fullmatch(r"select=(\d+) write=(\d+) merge=(\d+)\n", r.stdout).groups()
        jobs += list(bad_ids)
        for name, (recipe, _, _) in outs.items():
            common.occgt("build", "--json", recipe, "--out", os.path.join(root, name, "ref"), env=env)

        deadline = time.time() + TIMEOUT_S
        while True:
            r = subprocess.run(["squeue", "-h", "-j", ",".join(jobs), "-o", "%i %T %r"],
                               capture_output=True, text=True, env=env)
            if r.returncode == 0 and not r.stdout.strip():
                break  # (a non-zero exit, e.g. slurmctld busy, is retried until the deadline)
            if time.time() > deadline:
                raise AssertionError(f"jobs not done after {TIMEOUT_S} s:\n{r.stdout}{r.stderr}\n"
                                     + "".join(logs_of(o) for _, o, _ in outs.values()))
            time.sleep(0.5)
        t_jobs = time.time()
        print(f"{len(RECIPES)} recipes x (2 arrays of {NTASKS} tasks + merge) + a failing one: "
              f"{(len(RECIPES) + 1) * (2 * NTASKS + 1)} Slurm jobs done in {t_jobs - t_up:.1f} s")

        states = {}
        for job_id in bad_ids:
            states.update(job_states(env, job_id))
        assert sum(v == "FAILED" for v in states.values()) == NTASKS, states
        assert sum(v == "CANCELLED" for v in states.values()) in (2, NTASKS + 1), states
        assert "dataset.root: expected an existing folder" in logs_of(bad_out), logs_of(bad_out)
        print(f"failing select array: {NTASKS} tasks FAILED, write array and merge job cancelled "
              f"(--kill-on-invalid-dep): {sorted(states.values())}")

        for name, (recipe, out, ids) in outs.items():
            states = {}
            for job_id in ids:
                states.update(job_states(env, job_id))
            assert len(states) == 2 * NTASKS + 1, states
            bad = {k: v for k, v in states.items() if v != "COMPLETED"}
            assert not bad, f"{name}: jobs not COMPLETED: {bad}\n{logs_of(out)}"
            logs = logs_of(out)
            # Each array task took its own layout from SLURM_ARRAY_TASK_*.
            for k in range(NTASKS):
                assert logs.count(f"[build] task {k} of {NTASKS} (from SLURM_ARRAY_TASK_ID {k})") == 2, \
                    logs
            assert re.search(r"merged split \S+: \d+ shards", logs), logs
            n = common.assert_same_outputs(os.path.join(root, name, "ref"), out,
                                           skip_dirs=("slurm-logs",))
            assert not common.tmp_files(out), common.tmp_files(out)
            print(f"{name}: {n} files identical to the one-process run")
    finally:
        pids = [p for p in map(read_pid, pidfiles) if p]
        if jobs and os.path.exists(env["SLURM_CONF"]):
            subprocess.run(["scancel", *jobs], capture_output=True, env=env)
        subprocess.run(["bash", os.path.join(script_dir, "local_cluster.sh"), "stop", state],
                       stdin=subprocess.DEVNULL, env=env)
        left = [p for p in pids if alive(p)]
        assert not left, f"daemons still running: {left}"
    print(f"slurm: 1 passed, 0 failed ({time.time() - t_start:.1f} s)")


if __name__ == "__main__":
    main()
