"""The README's Quick start stays true: exactly two commands, the first the main job
(`scripts/occgt build` on a shipped recipe), the second `scripts/test`, which .ci/run calls.

The main command is run here with the built binary in place of `scripts/occgt` (which
only installs packages, builds, and then execs that binary), into a scratch folder; its
outputs must be the complete split that docs/USER_GUIDE.md describes.
"""
import json
import os
import re
import shlex
import sys

sys.path.insert(0, os.path.dirname(__file__))
import common  # noqa: E402


def quick_start_commands(readme):
    text = open(readme, encoding="utf-8").read()
    m = re.search(r"^## Quick start\n(.*?)(?=^## )", text, re.S | re.M)
    assert m, f"{readme}: no '## Quick start' section"
    # Commands are the indented (4-space) code lines of the section.
    return [line.strip() for line in m.group(1).splitlines() if line.startswith("    ") and line.strip()]


def main():
    readme = os.path.join(common.SOURCE, "README.md")
    cmds = quick_start_commands(readme)
    assert len(cmds) == 2, f"README Quick start must have exactly two commands, has {cmds}"
    main_cmd, test_cmd = cmds
    assert test_cmd == "scripts/test", test_cmd
    ci = open(os.path.join(common.SOURCE, ".ci", "run"), encoding="utf-8").read()
    assert re.search(r"^scripts/test\s*$", ci, re.M), ".ci/run must call the README's test command"

    argv = shlex.split(main_cmd)
    assert argv[:2] == ["scripts/occgt", "build"], f"main command is not occgt build: {main_cmd}"
    recipe = os.path.join(common.SOURCE, argv[2])
    assert os.path.isfile(recipe), f"README main command names a missing recipe: {argv[2]}"
    assert "--out" in argv, main_cmd
    out = common.scratch("readme_main")
    args = argv[2:]
    args[args.index("--out") + 1] = out
    args[0] = recipe
    r = common.occgt("build", *args)

    summary = json.load(open(os.path.join(out, "summary.json")))
    # The human summary on stdout (--json prints summary.json instead): its figures.
    first = r.stdout.splitlines()[0]
    assert f"{summary['samples']} pairs in {summary['scenes']} scenes" in first, r.stdout
    assert f"wrote {summary['samples_written_this_run']} pairs" in first, r.stdout
    for reason, n in summary["drops"].items():
        assert f"{reason} {n}" in r.stdout, (reason, r.stdout)
    assert "occgt inspect split " + out in r.stdout, r.stdout
    index = json.load(open(os.path.join(out, "index.json")))
    assert index["__kind__"] == "wids-shard-index-v1"
    shards = index["shardlist"]
    assert shards, "main job wrote no shard"
    for s in shards:
        p = os.path.join(out, s["url"])
        assert os.path.getsize(p) == s["filesize"], p
    n_pairs = sum(1 for _ in open(os.path.join(out, "pairs.jsonl")))
    assert n_pairs == sum(s["nsamples"] for s in shards) > 0
    leftovers = [os.path.join(d, f) for d, _, fs in os.walk(out) for f in fs if f.endswith(".tmp")]
    assert not leftovers, leftovers
    print(f"README main command: {len(shards)} shards, {n_pairs} pairs")


if __name__ == "__main__":
    main()
