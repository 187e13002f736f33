"""docs/EVAL.md's examples run as written: the loop (build the demo, the SIFT baseline,
occgt eval with two estimator settings; eval.json valid against its schema; the split
report with its evaluation section), the protocols block (glue-factory's protocol, a
sweep of two methods, the report with estimators side by side) and the
Python blocks that write predictions by sample key and by LoFTR pair name (read back by
occgt eval, whose only complaint is that the made-up pair is not in the demo split)."""
import json
import os
import re
import shlex
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "integration"))
import common  # noqa: E402


def block(text, name, lang):
    m = re.search(r"<!-- eval:%s -->\n```%s\n(.*?)```" % (name, lang), text, re.S)
    assert m, f"docs/EVAL.md: no {lang} block marked eval:{name}"
    return m.group(1)


def main():
    with open(os.path.join(common.SOURCE, "docs", "EVAL.md"), encoding="utf-8") as f:
        text = f.read()
    work = common.scratch("eval_docs")
    for line in block(text, "loop", "sh").strip().splitlines():
        argv = shlex.split(line)
        if argv[0] == "occgt":
            argv[0] = common.BINARY
        argv = [os.path.join(common.SOURCE, a) if a.startswith(("recipes/", "scripts/")) else a
                for a in argv]
        r = subprocess.run(argv, cwd=work, capture_output=True, text=True)
        assert r.returncode == 0, (line, r.returncode, r.stderr)
        if argv[0] == common.BINARY and argv[1] == "eval":
            assert "AUC" in r.stdout and "sift" in r.stdout, r.stdout
    with open(os.path.join(work, "out", "report", "report.html"), encoding="utf-8") as f:
        page = f.read()
    assert '<h2 id="eval">Evaluation</h2>' in page and 'data-set="sift"' in page
    assert os.path.exists(os.path.join(work, "out", "report", "eval_cumulative.png"))
    import jsonschema
    with open(os.path.join(work, "out", "eval.json")) as f:
        doc = json.load(f)
    with open(os.path.join(common.SOURCE, "schemas", "eval.schema.json")) as f:
        jsonschema.validate(doc, json.load(f), cls=jsonschema.Draft202012Validator)
    assert len(doc["options"]["estimators"]) == 2 and doc["sets"][0]["name"] == "sift"
    assert sum(p["sets"][0]["matches"] for p in doc["pairs"]) > 0

    # The protocols block: glue-factory's protocol (8 estimator settings, best of sweep),
    # a two-method sweep, and the report with the estimators side by side.
    for line in block(text, "protocols", "sh").strip().splitlines():
        argv = shlex.split(line)
        argv[0] = common.BINARY
        r = subprocess.run(argv, cwd=work, capture_output=True, text=True)
        assert r.returncode == 0, (line, r.returncode, r.stderr)
        if argv[1] == "eval":
            assert "optimistic" in r.stdout, r.stdout
    with open(os.path.join(work, "out", "gf.json")) as f:
        gf = json.load(f)
    assert len(gf["options"]["estimators"]) == 8 and gf["sets"][0]["selection"]["optimistic"]
    with open(os.path.join(work, "out", "sweep.json")) as f:
        sweep = json.load(f)
    assert [e["estimator"] for e in sweep["options"]["estimators"]] == ["ransac"] * 4 + \
        ["usac_magsac"] * 4
    with open(os.path.join(work, "out", "report_gf", "report.html"), encoding="utf-8") as f:
        page = f.read()
    assert "Estimators side by side" in page and "optimistic" in page
    assert os.path.exists(os.path.join(work, "out", "report_gf", "eval_estimator_disagreement.png"))

    # Each predictions block, run as written, is read back; the made-up pair is the only
    # complaint.
    for name, npz, complaint in (
            ("write", "predictions.npz",
             "pair scene0707_00/15_585 is not a sample of the split"),
            ("loftr", "loftr_predictions.npz",
             "pair scene0707_00/color/15.jpg#scene0707_00/color/585.jpg (a LoFTR pair name) "
             "is not a pair of the split")):
        subprocess.run(["/usr/bin/python3", "-c", block(text, name, "python")], cwd=work,
                       check=True)
        r = common.occgt("eval", os.path.join(work, "out", "demo"), "--predictions",
                         os.path.join(work, npz), "--out", os.path.join(work, "x.json"),
                         check=False)
        lines = r.stderr.splitlines()
        assert r.returncode == 1 and len(lines) == 1, (name, r.stderr)
        assert complaint in lines[0], (name, lines)
    print("docs/EVAL.md: loop, protocols, predictions and LoFTR-name examples ran")


if __name__ == "__main__":
    main()
