"""`occgt build` takes its task layout from a Slurm array task's environment when neither
--task nor --tasks is given (docs/CLI.md): task = SLURM_ARRAY_TASK_ID - SLURM_ARRAY_TASK_MIN
of SLURM_ARRAY_TASK_COUNT. Checks: a 2-task run driven only by the environment gives the
same files as one process, also with 4 tasks running at once (as an array on one machine);
an array starting at 1 maps to tasks 0..N-1; flags win (even
over a malformed variable); malformed or inconsistent values fail with one line naming the
variable before anything is created. No Slurm needed: the variables are set by hand."""
import json
import os
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common  # noqa: E402

SLURM_VARS = ("SLURM_ARRAY_TASK_ID", "SLURM_ARRAY_TASK_MIN", "SLURM_ARRAY_TASK_MAX",
              "SLURM_ARRAY_TASK_COUNT", "SLURM_ARRAY_TASK_STEP")


def slurm_env(**values):
    env = {k: v for k, v in os.environ.items() if k not in SLURM_VARS}
    env.update({f"SLURM_ARRAY_TASK_{k.upper()}": str(v) for k, v in values.items()})
    return env


def main():
    root = common.scratch("build_slurm_env")
    recipe, _, _ = common.demo_recipe(root)  # half size under a sanitizer
    ref = os.path.join(root, "ref")
    common.occgt("build", "--json", recipe, "--out", ref, env=slurm_env())

    # Two array tasks (0-1), select then write, layout from the environment only.
    out = os.path.join(root, "env")
    for stage in ("select", "write"):
        for task in (1, 0):
            env = slurm_env(id=task, min=0, max=1, count=2)
            r = common.occgt("build", "--json", recipe, "--out", out, "--stage", stage, env=env)
            s = json.loads(r.stdout)
            assert (s["task"], s["tasks"]) == (task, 2), s
            assert f"[build] task {task} of 2 (from SLURM_ARRAY_TASK_ID {task})" in r.stderr, r.stderr
            if stage == "select" and task == 1:
                assert sorted(os.listdir(os.path.join(out, "selection"))) == \
                    ["synth_001.json", "synth_001.jsonl"], "task 1 of 2 takes the second scene only"
    n = common.assert_same_outputs(ref, out)

    # An array on one machine: 4 tasks at once per stage (they share recipe.json, the
    # synthetic dataset they generate, the shard plan and the indices: DIR/.lock).
    out4 = os.path.join(root, "concurrent")
    for stage in ("select", "write"):
        procs = [subprocess.Popen([common.BINARY, "build", "--json", recipe, "--out", out4, "--stage", stage],
                                  env=slurm_env(id=k, min=0, max=3, count=4),
                                  stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
                 for k in range(4)]
        for p in procs:
            _, err = p.communicate()
            assert p.returncode == 0, f"concurrent {stage} task failed:\n{err}"
    common.assert_same_outputs(ref, out4)
    assert not common.tmp_files(out4), common.tmp_files(out4)

    # An array 1-2 (no MIN: 0 assumed only when unset) gives tasks 0 and 1; COUNT from MAX.
    out1 = os.path.join(root, "from1")
    for array_id in (1, 2):
        r = common.occgt("build", "--json", recipe, "--out", out1, "--stage", "select", "--dry-run",
                         env=slurm_env(id=array_id, min=1, max=2))
        s = json.loads(r.stdout)
        assert (s["task"], s["tasks"]) == (array_id - 1, 2), s

    # Flags win, also over a malformed variable.
    for env in (slurm_env(id=1, min=0, max=1, count=2), slurm_env(id="x", count="y")):
        r = common.occgt("build", "--json", recipe, "--out", out, "--tasks", "1", env=env)
        s = json.loads(r.stdout)
        assert (s["task"], s["tasks"]) == (0, 1) and "[build] task" not in r.stderr, (s, r.stderr)
        r = common.occgt("build", "--json", recipe, "--out", out, "--task", "0", env=env)
        assert (json.loads(r.stdout)["tasks"]) == 1

    # Bad values: one line naming the variable, exit 1, nothing created.
    cases = [
        (dict(id="3x", count=4), "SLURM_ARRAY_TASK_ID: expected an integer >= 0, got '3x'"),
        (dict(id="-1", count=4), "SLURM_ARRAY_TASK_ID: expected an integer >= 0, got '-1'"),
        (dict(id=0, count="four"), "SLURM_ARRAY_TASK_COUNT: expected an integer >= 0, got 'four'"),
        (dict(id=0, min=" 0", count=1), "SLURM_ARRAY_TASK_MIN: expected an integer >= 0, got ' 0'"),
        (dict(id=0), "SLURM_ARRAY_TASK_COUNT: unset (and no SLURM_ARRAY_TASK_MAX)"),
        (dict(id=2, min=0, max=6, count=4), "SLURM_ARRAY_TASK_COUNT: 4 tasks do not fill the array 0-6"),
        (dict(id=5, min=0, max=3, count=4), "SLURM_ARRAY_TASK_ID: 5 outside the array 0-3"),
        (dict(id=4, count=4), "SLURM_ARRAY_TASK_COUNT: 4 does not cover SLURM_ARRAY_TASK_ID 4"),
        (dict(id=0, count=0), "SLURM_ARRAY_TASK_COUNT: 0 does not cover SLURM_ARRAY_TASK_ID 0"),
        # A stepped array without COUNT (MAX gives 7 tasks, of which 4 run): refused.
        (dict(id=2, min=0, max=6, step=2), "SLURM_ARRAY_TASK_STEP: 2: expected 1"),
    ]
    for values, expected in cases:
        bad = os.path.join(root, "bad")
        r = common.occgt("build", "--json", recipe, "--out", bad, env=slurm_env(**values), check=False)
        lines = r.stderr.strip().splitlines()
        assert r.returncode == 1, (values, r.returncode, r.stderr)
        assert len(lines) == 1 and lines[0].startswith("occgt: error: " + expected), (values, r.stderr)
        assert not os.path.exists(bad), f"{values}: output created before the check"
    # --tasks without --task would run task 0 in every task of an array: a usage error.
    r = common.occgt("build", recipe, "--out", os.path.join(root, "bad"), "--tasks", "3",
                     env=slurm_env(id=1, count=3), check=False)
    assert r.returncode == 2 and r.stderr.startswith(
        "occgt: error: --tasks: 3 needs --task K (0 <= K < 3): alone it would run task 0"), \
        (r.returncode, r.stderr)
    print(f"build_slurm_env: 1 passed, 0 failed ({n} files identical, {len(cases)} bad cases)")


if __name__ == "__main__":
    main()
