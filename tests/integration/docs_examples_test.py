"""Every shell example of docs/*.md and README.md is accounted for, and runs.

A command line of an example block (indented or fenced, not Python: the Python blocks run in
tests/python/docs_test.py, reading_shards_test.py, tests/eval/docs_test.py and
occupancy's) is one of:
- RUN_HERE: run below as written, with `occgt` on PATH, from a folder where `../shared/data`
  is the real samples and `out/demo` the demo build;
- FILLED: a template over the user's own recipe and folders (`r.yaml`, `my.yaml`,
  `/shards/x`, `$K`): run below with those filled in (the demo recipe, a scratch folder);
- ELSEWHERE: run as written by the named test, which names the page;
- NOT_RUN: with the reason (the user's ScanNet, a long run of what CI runs short).
Usage synopses (`[--flag]`, `DIR`, `RECIPE`) and printed output are not commands.
A new example line that is in none of these lists fails this test.
"""
import glob
import os
import re
import shutil
import subprocess
import sys

sys.path.insert(0, os.path.dirname(__file__))
import common  # noqa: E402

RUN_HERE = {
    "docs/CLI.md": [
        "occgt render --root ../shared/data/sevenscenes --format sevenscenes --scene rgbd-frames "
        "--mesh ../shared/data/meshes/sevenscenes-rgbd-frames-tsdf.ply --frames 000150,000175 "
        "--out out/render",
    ],
    "docs/INSPECT.md": [
        "occgt inspect pair --shard out/demo/demo-000000.tar --key synth_000/000000_000001 --out pics",
        "occgt inspect pair --pair-dir pairdir --root ../shared/data/tartanair/hospital_sample --out pics",
        "occgt inspect pair --root ../shared/data/tartanair/hospital_sample --format tartanair "
        "--scene hospital_sample --frames 000000,000020 --out pics",
        "occgt inspect pair --root ../shared/data/sevenscenes --format sevenscenes --scene "
        "rgbd-frames --frames 000150,000175 --mesh "
        "../shared/data/meshes/sevenscenes-rgbd-frames-tsdf.ply --depth-source fused "
        "--no-occupancy --out pics",
        "occgt inspect split out/demo",
        "occgt inspect split out/demo --out report --gallery 6 --seed 0 --aggregate mean "
        "--occlusion-metric image --bins 20",
    ],
}
FILLED = {
    "docs/SCALE.md": [
        "for k in $(seq 0 7); do occgt build r.yaml --out /shards/x --tasks 8 --task $k --stage select; done",
        "for k in $(seq 0 7); do occgt build r.yaml --out /shards/x --tasks 8 --task $k --stage write; done",
        "occgt merge /shards/x",
    ],
    "docs/USER_GUIDE.md": [
        "occgt build my.yaml --out /shards/x --dry-run",
        "occgt build r.yaml --out /shards/x --tasks 8 --task $K --stage select",
        "occgt build r.yaml --out /shards/x --tasks 8 --task $K --stage write",
        "occgt merge /shards/x",
    ],
}
ELSEWHERE = {
    "docs/RECIPES.md": {
        "occgt covis recipes/tartanair-tuples.yaml --out out/ta-tuples --dense":
            "python/covis_test.py",
        "occgt tuples recipes/tartanair-tuples.yaml --out out/ta-tuples": "python/covis_test.py",
        "occgt tuples recipes/tartanair-tuples.yaml --out out/ta-tuples --shards":
            "python/views_shards_test.py",
    },
    "README.md": {"scripts/occgt build recipes/demo.yaml --out out/demo": "integration/readme_test.py",
                  "scripts/test": "integration/readme_test.py"},
    "docs/USER_GUIDE.md": {
        "scripts/occgt build recipes/demo.yaml --out out/demo": "integration/readme_test.py",
        "scripts/setup.sh --install": "integration/install_test.py",
        "scripts/slurm/submit.sh r.yaml /shards/x 8": "integration/slurm_test.py",
    },
    "docs/CLI.md": {
        "$ occgt scan ../shared/data/tartanair/hospital_sample --format tartanair --check-depth":
            "integration/scan_test.py",
        "$ occgt synth --out out/synth --scenes 1 --frames 5 --resolution 160x120":
            "integration/synth_test.py",
        "$ occgt scan out/synth --format generic": "integration/synth_test.py",
        "occgt build recipes/tartanair-sample.yaml --out out/ta": "integration/pair_recipe_test.py",
        "occgt pair --recipe recipes/tartanair-sample.yaml --scene hospital_sample --frames "
        "000000,000004 --out out/ta_pair": "integration/pair_recipe_test.py",
        "occgt occupancy --recipe recipes/tartanair-sample.yaml --scene hospital_sample --frames "
        "000000,000004 --out out/ta_pair": "integration/pair_recipe_test.py",
    },
    "docs/EVAL.md": {
        "occgt build recipes/demo.yaml --out out/demo": "eval/docs_test.py",
        "/usr/bin/python3 scripts/eval_sift_baseline.py out/demo out/sift.npz": "eval/docs_test.py",
        "occgt eval out/demo --predictions out/sift.npz --ransac-px 0.5,1.0 --out out/eval.json":
            "eval/docs_test.py",
        "occgt inspect split out/demo --eval out/eval.json --out out/report": "eval/docs_test.py",
        "occgt eval out/demo --predictions out/sift.npz --protocol gluefactory --out out/gf.json":
            "eval/docs_test.py",
        "occgt eval out/demo --predictions out/sift.npz --estimator ransac,usac_magsac "
        "--ransac-px sweep --out out/sweep.json": "eval/docs_test.py",
        "occgt inspect split out/demo --eval out/gf.json --out out/report_gf": "eval/docs_test.py",
    },
    "docs/PYTHON.md": {
        "scripts/setup.sh": "python/install_test.py",
        "/usr/bin/python3 -m venv --system-site-packages ~/occgt-venv": "python/install_test.py",
        "~/occgt-venv/bin/pip install --no-build-isolation ./python": "python/install_test.py",
        "~/occgt-venv/bin/python -c \"import occgt; print(occgt.__version__)\"":
            "python/install_test.py",
    },
    "docs/SCALE.md": {
        "sudo scripts/slurm/local_cluster.sh start /tmp/slurm-state": "integration/slurm_test.py",
        "export SLURM_CONF=/tmp/slurm-state/slurm.conf": "integration/slurm_test.py",
        "scripts/slurm/submit.sh recipes/demo.yaml /tmp/demo-slurm 4": "integration/slurm_test.py",
        "squeue": "integration/slurm_test.py",
        "sudo scripts/slurm/local_cluster.sh stop /tmp/slurm-state": "integration/slurm_test.py",
    },
    "docs/RELIABILITY.md": {
        "scripts/fuzz.sh --smoke": "../.ci/run",
        "scripts/test-sanitize asan": "../.ci/run",
        "scripts/test-sanitize tsan": "../.ci/run",
    },
}
NOT_RUN = {
    "docs/USER_GUIDE.md": {
        "occgt scan /data/scannet/scans --format scannet": "the user's ScanNet; ../shared/data "
        "has no ScanNet depth",
        "SCANNET_ROOT=/data/scannet/scans occgt build recipes/scannet-train.yaml --out "
        "/shards/train": "the user's ScanNet",
        "occgt build recipes/scannet-train.yaml --root /data/scannet/scans --out /shards/train":
            "the user's ScanNet",
    },
    "docs/RELIABILITY.md": {
        "scripts/fuzz.sh --runs 100000": "a long run of the smoke run CI does",
        "scripts/fuzz.sh --seconds 60 --only recipe": "a long run of the smoke run CI does",
    },
    "docs/PERFORMANCE.md": {
        "tests/bench/e2e_bench.py --reps 5 --json e2e.json": "a benchmark: timed by hand, never "
        "in tests",
    },
}

COMMAND = re.compile(r"(\$ )?(occgt|scripts/|tests/|sudo |export |squeue|for |SCANNET_ROOT=|"
                     r"PYTHONPATH=|/usr/bin/python3|~/occgt-venv|cmake)")
SYNOPSIS = re.compile(r"\[--|\b(ROOT|DIR|RECIPE|SPLIT_DIR|NTASKS)\b|X\.tar")


def example_lines(path):
    """Command lines of the shell examples of one page (continuations joined, comments cut)."""
    lines = open(path, encoding="utf-8").read().split("\n")
    out, fence, i = [], None, 0
    while i < len(lines):
        line = lines[i]
        i += 1
        if line.startswith("```"):
            fence = None if fence is not None else (line[3:].strip() or "text")
            continue
        if fence == "python" or (fence is None and not line.startswith("    ")):
            continue
        text = line.strip()
        while text.endswith("\\") and i < len(lines):
            text = text[:-1].rstrip() + " " + lines[i].strip()
            i += 1
        text = "" if text.startswith("#") else re.sub(r"\s+#.*$", "", text)
        if COMMAND.match(text) and not text.startswith("occgt: error:") and \
                not SYNOPSIS.search(text):
            out.append(text)
    return out


def inventory():
    found = {}
    for path in sorted(glob.glob(os.path.join(common.SOURCE, "docs", "*.md"))) + [
            os.path.join(common.SOURCE, "README.md")]:
        rel = os.path.relpath(path, common.SOURCE)
        for text in example_lines(path):
            found.setdefault(rel, []).append(text)
    return found


def check_inventory(found):
    unknown = []
    for page, lines in found.items():
        known = set(RUN_HERE.get(page, [])) | set(FILLED.get(page, [])) | \
            set(ELSEWHERE.get(page, {})) | set(NOT_RUN.get(page, {}))
        unknown += [f"{page}: {t}" for t in lines if t not in known]
    assert not unknown, "example lines that no test runs and no list accounts for:\n  " + \
        "\n  ".join(unknown)
    # Every listed line is still on its page (a list never outlives its example).
    for table in (RUN_HERE, FILLED, ELSEWHERE, NOT_RUN):
        for page, lines in table.items():
            for text in lines:
                assert text in found.get(page, []), f"{page}: listed but not found: {text}"
    # The tests named as running a page's examples exist and name that page.
    tests = os.path.join(common.SOURCE, "tests")
    for page, entries in ELSEWHERE.items():
        for text, test in entries.items():
            path = os.path.normpath(os.path.join(tests, test))
            body = open(path, encoding="utf-8").read()
            # The test names the page, or runs the very script the line calls.
            script = text.split()[1] if text.startswith("sudo ") else text.split()[0]
            assert os.path.basename(page) in body or os.path.basename(script) in body or \
                text in body, f"{test} does not run {page}'s '{text}'"


def workspace():
    """ws/ with out/demo built and ../shared/data pointing at the real samples."""
    root = common.scratch("docs_examples")
    os.makedirs(os.path.join(root, "shared"))
    os.symlink(os.path.abspath(common.SHARED), os.path.join(root, "shared", "data"))
    ws = os.path.join(root, "ws")
    os.makedirs(ws)
    common.occgt("build", os.path.join(common.SOURCE, "recipes", "demo.yaml"), "--out",
                 os.path.join(ws, "out", "demo"))
    return ws


def run(ws, text, env):
    r = subprocess.run(["bash", "-c", "set -euo pipefail; " + text], cwd=ws, env=env,
                       capture_output=True, text=True)
    assert r.returncode == 0, f"{text}\nexit {r.returncode}\n{r.stdout}{r.stderr}"
    return r.stdout


def main():
    common.shared("tartanair/hospital_sample")
    check_inventory(inventory())
    ws = workspace()
    env = dict(os.environ, PATH=os.path.dirname(common.BINARY) + os.pathsep + os.environ["PATH"])

    # INSPECT.md, as written. The `occgt pair` folder its second line reads is made first,
    # the way the page says: `occgt pair` and `occgt occupancy` into one folder.
    common.occgt("pair", "--root", common.shared("tartanair/hospital_sample"), "--format",
                 "tartanair", "--scene", "hospital_sample", "--frames", "000000,000004",
                 "--resolution", "160x120", "--out", os.path.join(ws, "pairdir"))
    common.occgt("occupancy", "--root", common.shared("tartanair/hospital_sample"), "--format",
                 "tartanair", "--scene", "hospital_sample", "--frames", "000000,000004",
                 "--resolution", "160x120", "--out", os.path.join(ws, "pairdir"))
    for text in RUN_HERE["docs/INSPECT.md"]:
        shutil.rmtree(os.path.join(ws, "pics"), ignore_errors=True)
        run(ws, text, env)
        if "inspect pair" in text:
            made = sorted(os.listdir(os.path.join(ws, "pics")))
            assert "labels.png" in made or "occupancy.png" in made, (text, made)
            if "--depth-source" in text:  # a scene with a mesh: the depth panels too
                assert "depth.png" in made, (text, made)
    for text in RUN_HERE["docs/CLI.md"]:  # occgt render on the 7-Scenes sample
        run(ws, text, env)
        assert os.path.isfile(os.path.join(ws, "out", "render", "000175_depth.png")), text
    for folder in ("out/demo/inspect", "report"):
        assert os.path.isfile(os.path.join(ws, folder, "report.html")), folder

    # The templates, with the user's recipe = the demo recipe and /shards = a scratch folder.
    # 8 tasks through both stages, by hand, must give the files of one `occgt build`.
    shutil.copy(os.path.join(common.SOURCE, "recipes", "demo.yaml"), os.path.join(ws, "r.yaml"))
    shutil.copy(os.path.join(common.SOURCE, "recipes", "demo.yaml"), os.path.join(ws, "my.yaml"))

    def fill(text, k=None):
        text = text.replace("/shards/", "shards/")
        return text.replace("$K", str(k)) if k is not None else text

    for page in ("docs/SCALE.md", "docs/USER_GUIDE.md"):
        shutil.rmtree(os.path.join(ws, "shards"), ignore_errors=True)
        for text in FILLED[page]:
            if "$K" in text:
                for k in range(8):
                    run(ws, fill(text, k), env)
            else:
                out = run(ws, fill(text), env)
                if "--dry-run" in text:
                    assert "pairs in 2 scenes" in out, out
        if page == "docs/SCALE.md":
            one = os.path.join(ws, "one")
            common.occgt("build", os.path.join(ws, "r.yaml"), "--out", one)
            x = os.path.join(ws, "shards", "x")
            for name in sorted(os.listdir(one)):
                if name.endswith(".tar") or name in ("index.json", "pairs.jsonl"):
                    with open(os.path.join(one, name), "rb") as a, \
                            open(os.path.join(x, name), "rb") as b:
                        same = a.read() == b.read()
                    assert same, f"{name}: 8 tasks by hand differ from one build"
    print("docs examples: every example line accounted for; INSPECT, SCALE and USER_GUIDE ran")


if __name__ == "__main__":
    main()
