"""The ground truth of the shipped recipes stays byte-identical: every .npy member of every
shard of recipes/demo.yaml, sevenscenes-sample.yaml and tartanair-sample.yaml has the MD5
recorded in tests/golden/<recipe>.txt (tests/golden/npy_digests.py), whatever the thread
count. A refactor that changes one array fails here with the member's name. Record anew,
deliberately, only when a change of the ground truth is intended (the commit says why)."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "golden"))
import common  # noqa: E402
import npy_digests  # noqa: E402


def check(recipe, threads):
    if recipe != "demo":
        common.shared("sevenscenes" if recipe.startswith("seven") else "tartanair")
    env = dict(os.environ, OCCGT_SHARED_DATA=common.SHARED)
    out = common.scratch(f"golden_{recipe}_t{threads}")
    common.occgt("build", "--json", os.path.join(common.SOURCE, "recipes", recipe + ".yaml"), "--out", out,
                 "--threads", threads, env=env)
    got = npy_digests.digests(out)
    with open(os.path.join(common.SOURCE, "tests", "golden", recipe + ".txt")) as f:
        want = f.read().split("\n")
    want = [w for w in want if w]
    assert len(got) == len(want), (recipe, len(got), len(want))
    bad = [(g, w) for g, w in zip(got, want) if g != w]
    assert not bad, f"{recipe} --threads {threads}: {len(bad)} members differ, first {bad[0]}"
    return len(got)


def main():
    n = 0
    for recipe in ("demo", "sevenscenes-sample", "tartanair-sample"):
        for threads in (1, 2):
            n += check(recipe, threads)
    print(f"golden: {n} .npy members identical to tests/golden/")


if __name__ == "__main__":
    main()
