"""The evaluation section of the split report (`occgt inspect split DIR --eval eval.json`,
docs/EVAL.md "The report"), end to end on the demo split: two eval files, three sets
(ground-truth matches, matches moved by 6 px noise with random confidences, both
read with --min-confidence, matches shifted by 12 px). The page's tables equal eval.json; each set's
gallery shows the worst pairs in the documented order, and the per-class counts re-scored
for the pictures equal eval.json's; the page opens in headless Chromium with every image
decoded; the output is deterministic; an eval.json of version 1 (the old names of
consistent_overlap) gives the same page; bad eval files fail with one line and exit 1 (a bad
--eval-gallery: 2); a
predictions file that is gone is said on the page, not fatal."""
import html
import json
import math
import os
import re
import shutil
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "integration"))
import common  # noqa: E402
import inspect_test  # noqa: E402  (chromium_check, png, not_blank)
import predictions  # noqa: E402


def save(path, pairs, confidence=None):
    arrays = {}
    for key, (k0, k1) in pairs.items():
        arrays[key + "/kpts0"] = np.asarray(k0, np.float32)
        arrays[key + "/kpts1"] = np.asarray(k1, np.float32)
        if confidence is not None:
            arrays[key + "/confidence"] = confidence[key]
    np.savez(path, **arrays)


def worst(doc, k, count):
    """The documented gallery order: failures first, then larger pose error, then lower
    epipolar precision, then split order; pairs without a prediction left out."""
    rows = []
    for i, p in enumerate(doc["pairs"]):
        s = p["sets"][k]
        if not s["predicted"]:
            continue
        err = s["pose"][0]["error_deg"]
        rows.append((-(math.inf if err is None else err), s["epipolar_precision"], i, p["key"]))
    rows.sort()
    return [r[3] for r in rows[:count]]


def section_rows(page, table_class):
    m = re.search(r'<table class="%s">(.*?)</table>' % table_class, page, re.S)
    assert m, table_class
    rows = re.findall(r'<tr data-set="([^"]*)">(.*?)</tr>', m.group(1), re.S)
    return [(html.unescape(name), [html.unescape(c) for c in re.findall(r"<td[^>]*>(.*?)</td>", r)])
            for name, r in rows]


def fmt(v, d):
    return "-" if v is None else "%.*f" % (d, v)


def main():
    work = common.scratch("eval_report")
    split = os.path.join(work, "demo")
    common.occgt("build", "--json", os.path.join(common.SOURCE, "recipes", "demo.yaml"), "--out", split)
    rng = np.random.default_rng(5)
    truth, noisy, shifted, conf = {}, {}, {}, {}
    for s in predictions.iter_samples(split):
        key = s["__key__"]
        W, H = s["json"]["resolution"]
        k0, k1, _ = predictions.truth_matches(s)
        truth[key] = (k0, k1)
        hi = np.array([W - 0.51, H - 0.51], np.float32)
        noisy[key] = (k0, np.clip(k1 + rng.normal(0, 6, k1.shape), -0.5, hi).astype(np.float32))
        conf[key] = rng.uniform(0, 1, len(k0)).astype(np.float32)
        shifted[key] = (k0, np.clip(k1 + np.float32([12, 0]), -0.5, hi).astype(np.float32))
    preds = os.path.join(work, "preds")
    os.makedirs(preds, exist_ok=True)
    save(os.path.join(preds, "gt.npz"), truth, {k: np.ones(len(v[0]), np.float32) for k, v in truth.items()})
    save(os.path.join(preds, "noisy.npz"), noisy, conf)
    save(os.path.join(preds, "shifted.npz"), shifted)

    # Two eval files: a.json (gt, noisy with --min-confidence 0.3), b.json (a set also named
    # "gt": the two are shown as "a:gt" and "b:gt").
    a_json, b_json = os.path.join(work, "a.json"), os.path.join(work, "b.json")
    common.occgt("eval", split, "--out", a_json, "--predictions", os.path.join(preds, "gt.npz"),
                 "--predictions", os.path.join(preds, "noisy.npz"), "--min-confidence", "0.3")
    common.occgt("eval", split, "--out", b_json,
                 "--predictions", "gt=" + os.path.join(preds, "shifted.npz"))
    a, b = predictions.load_json(a_json), predictions.load_json(b_json)
    predictions.check_eval_schema(a, common.SOURCE)
    assert a["options"]["min_confidence"] == 0.3 and b["options"]["min_confidence"] == 0
    out = os.path.join(work, "report")
    r = common.occgt("inspect", "split", split, "--eval", a_json, "--eval", b_json, "--out", out)
    for name in ("eval_cumulative.png", "eval_auc_by_occlusion.png", "eval_auc_by_overlap.png"):
        assert os.path.join(out, name) in r.stdout, r.stdout
        inspect_test.not_blank(inspect_test.png(os.path.join(out, name)), name)
    report = os.path.join(out, "report.html")
    with open(report, encoding="utf-8") as f:
        page = f.read()
    assert '<h2 id="eval">Evaluation</h2>' in page

    sets = [("a:gt", a, 0), ("noisy", a, 1), ("b:gt", b, 0)]
    # Tables: the numbers of eval.json, as printed.
    pose_rows = section_rows(page, "eval-pose")
    assert [n for n, _ in pose_rows] == [n for n, _, _ in sets], pose_rows
    for (label, doc, k), (_, cells) in zip(sets, pose_rows):
        overall = doc["sets"][k]["overall"]
        pose = overall["pose"][0]
        assert cells[2:5] == [fmt(x, 2) for x in pose["auc_percent"]], (label, cells)
        assert cells[5] == str(pose["failures"]) and cells[6] == str(doc["sets"][k]["pairs_missing"])
        assert cells[7] == fmt(overall["matches_mean"], 1), (label, cells)
        assert cells[8] == fmt(overall["epipolar_precision_percent"], 1), (label, cells)
    type_rows = section_rows(page, "eval-types")
    for (label, doc, k), (_, cells) in zip(sets, type_rows):
        types = doc["sets"][k]["overall"]["types"]
        for j, t in enumerate(("vv", "vo", "ov")):
            x = types[t]
            assert cells[1 + 2 * j] == "%s (%d/%d)" % (fmt(x["precision_percent"], 1), x["correct"],
                                                        x["predicted"]), (label, t, cells)
            assert cells[2 + 2 * j] == "%s (%d/%d)" % (fmt(x["recall_percent"], 1), x["recalled"],
                                                        x["truth"]), (label, t, cells)
    # Ground truth is perfect, noise and shift are not: the table says so.
    assert type_rows[0][1][1].startswith("100.0") and not type_rows[2][1][1].startswith("100.0")

    # Galleries: the worst pairs in order, each with its picture; the counts re-scored for
    # the picture equal eval.json's (another code path: one sample read from its shard).
    galleries = re.split(r'<h3 class="eval-gallery" data-set="', page)[1:]
    assert len(galleries) == 3, len(galleries)
    for (label, doc, k), g in zip(sets, galleries):
        assert html.unescape(g[: g.index('"')]) == label
        g = g.split("<h2>", 1)[0]
        captions = [html.unescape(c) for c in re.findall(r"<h4>(.*?)</h4>", g)]
        expected = worst(doc, k, 4)
        assert [c.split()[0] for c in captions] == expected, (label, captions, expected)
        assert g.count("<img ") == len(expected), label
        by_key = {p["key"]: p["sets"][k] for p in doc["pairs"]}
        for c in captions:
            s = by_key[c.split()[0]]
            assert "%d matches" % s["matches"] in c, (c, s["matches"])
            for t in ("vv", "vo", "ov"):
                predicted, correct = s["types"][t][0], s["types"][t][1]
                assert "%s %d/%d" % (t, correct, predicted) in c, (c, t, s["types"][t])
            assert "unscored %d" % s["types"]["unscored"] in c, c
    # The noisy set was filtered by confidence: fewer matches than ground truth.
    noisy_mean = a["sets"][1]["overall"]["matches_mean"]
    assert noisy_mean < 0.8 * a["sets"][0]["overall"]["matches_mean"], noisy_mean

    # Headless Chromium: every image decodes, no console error.
    tmp = os.path.join(work, "chromium")
    os.makedirs(tmp, exist_ok=True)
    inspect_test.chromium_check(report, tmp)
    assert not inspect_test.failures, inspect_test.failures

    # Deterministic: the same page again.
    out2 = os.path.join(work, "report2")
    common.occgt("inspect", "split", split, "--eval", a_json, "--eval", b_json, "--out", out2)
    with open(os.path.join(out2, "report.html"), encoding="utf-8") as f:
        assert f.read() == page, "report.html differs between two runs"

    # eval.json of version 1 (the pair metric consistent_overlap then named
    # options.overlap_bins, sets[].by_visible_overlap, pairs[].visible_overlap) still reads:
    # the same page but for the files' folder.
    v1 = os.path.join(work, "v1")
    os.makedirs(v1, exist_ok=True)
    for src in (a_json, b_json):
        old = predictions.load_json(src)
        assert old["version"] == 2, old["version"]
        old["version"] = 1
        old["options"]["overlap_bins"] = old["options"].pop("consistent_overlap_bins")
        for s in old["sets"]:
            s["by_visible_overlap"] = s.pop("by_consistent_overlap")
        for p in old["pairs"]:
            p["visible_overlap"] = p.pop("consistent_overlap")
        with open(os.path.join(v1, os.path.basename(src)), "w") as f:
            json.dump(old, f, indent=1, sort_keys=True)
    out_v1 = os.path.join(work, "report_v1")
    common.occgt("inspect", "split", split, "--eval", os.path.join(v1, "a.json"), "--eval",
                 os.path.join(v1, "b.json"), "--out", out_v1)
    with open(os.path.join(out_v1, "report.html"), encoding="utf-8") as f:
        page_v1 = f.read()
    assert v1 + "/a.json" in page_v1, "the version-1 files are not named"
    assert page_v1.replace(v1 + "/", work + "/") == page, "a version-1 eval.json reads otherwise"

    # Predictions gone: the page says so, the rest is written.
    moved = os.path.join(work, "moved")
    os.makedirs(moved, exist_ok=True)
    shutil.copy(b_json, os.path.join(moved, "b.json"))
    os.rename(os.path.join(preds, "shifted.npz"), os.path.join(preds, "shifted.gone"))
    r = common.occgt("inspect", "split", split, "--eval", os.path.join(moved, "b.json"), "--out",
                     os.path.join(work, "report3"))
    with open(os.path.join(work, "report3", "report.html"), encoding="utf-8") as f:
        p3 = f.read()
    assert "were not found" in p3 and "shifted.npz" in p3, "no warning for the missing predictions"
    # ... and stderr (a script sees it; it was on the page only).
    said = [l for l in r.stderr.splitlines() if l.startswith("occgt: warning: ")]
    assert any(": No gallery: the predictions '" in l and "shifted.npz" in l and
               "were not found" in l for l in said), r.stderr
    os.rename(os.path.join(preds, "shifted.gone"), os.path.join(preds, "shifted.npz"))
    # ... found next to the eval.json when the path is relative.
    rel = os.path.join(work, "rel")
    os.makedirs(rel, exist_ok=True)
    shutil.copy(os.path.join(preds, "gt.npz"), os.path.join(rel, "mine.npz"))
    doc = predictions.load_json(a_json)
    doc["sets"][0]["path"] = "mine.npz"
    with open(os.path.join(rel, "e.json"), "w") as f:
        json.dump(doc, f)
    common.occgt("inspect", "split", split, "--eval", os.path.join(rel, "e.json"), "--out",
                 os.path.join(work, "report4"))
    with open(os.path.join(work, "report4", "report.html"), encoding="utf-8") as f:
        p4 = f.read()
    assert p4.count("were not found") == 0, "mine.npz next to e.json not found"

    # Estimators side by side: a sweep of two methods on the noisy set. One row per
    # estimator with the AUCs of eval.json and their mean; the best-of-sweep row starred and
    # called optimistic; the disagreement plot drawn (and absent with one estimator).
    sw_json = os.path.join(work, "sweep.json")
    common.occgt("eval", split, "--out", sw_json, "--predictions", os.path.join(preds, "noisy.npz"),
                 "--estimator", "ransac,usac_magsac", "--ransac-px", "sweep")
    sw = predictions.load_json(sw_json)
    predictions.check_eval_schema(sw, common.SOURCE)
    out5 = os.path.join(work, "report5")
    r = common.occgt("inspect", "split", split, "--eval", sw_json, "--out", out5)
    dis = os.path.join(out5, "eval_estimator_disagreement.png")
    assert dis in r.stdout, r.stdout
    inspect_test.not_blank(inspect_test.png(dis), "disagreement")
    with open(os.path.join(out5, "report.html"), encoding="utf-8") as f:
        p5 = f.read()
    m = re.search(r'<table class="eval-estimators">(.*?)</table>', p5, re.S)
    assert m and "optimistic" in p5, "no estimators table"
    rows = re.findall(r'<tr data-set="noisy"( class="best")?>(.*?)</tr>', m.group(1), re.S)
    est = sw["options"]["estimators"]
    assert len(rows) == len(est) == 8, len(rows)
    best = sw["sets"][0]["selection"]["best"]
    for e, (star, row) in enumerate(rows):
        cells = [html.unescape(c) for c in re.findall(r"<td[^>]*>(.*?)</td>", row, re.S)]
        auc = sw["sets"][0]["overall"]["pose"][e]["auc_percent"]
        assert cells[2] == "%g" % est[e]["ransac_px"], cells
        assert cells[3] == " / ".join(fmt(x, 2) for x in auc), (cells, auc)
        assert cells[4].startswith(fmt(sum(auc) / len(auc), 2)), cells
        assert bool(star) == (e == best) and cells[4].endswith("★") == (e == best), (e, cells)
    assert not os.path.exists(os.path.join(out, "eval_estimator_disagreement.png"))
    assert "Estimators side by side" not in page

    # Bad eval files: one line naming the file, exit 1 (bad input; usage errors exit 2), no
    # report written.
    def bad(name, doc_or_text, expect, extra=()):
        path = os.path.join(work, name)
        with open(path, "w") as f:
            f.write(doc_or_text if isinstance(doc_or_text, str) else json.dumps(doc_or_text))
        dest = os.path.join(work, "bad_" + name)
        r = common.occgt("inspect", "split", split, "--eval", path, *extra, "--out", dest, check=False)
        lines = r.stderr.strip().splitlines()
        assert r.returncode == 1, (name, r.returncode, r.stderr)
        assert len(lines) == 1 and path in lines[0] and expect in lines[0], (name, r.stderr)
        assert not os.path.exists(os.path.join(dest, "report.html")), name

    other = predictions.load_json(a_json)
    other["pairs"] = other["pairs"][1:]
    bad("fewer.json", other, "pairs")
    bad("text.json", "{not json", "not valid JSON")
    bad("summary.json", predictions.load_json(os.path.join(split, "summary.json")), "kind/version")
    future = predictions.load_json(a_json)
    future["version"] = 3
    bad("future.json", future, "kind/version")
    old_missing = predictions.load_json(a_json)  # version 1 without its overlap_bins
    old_missing["version"] = 1
    del old_missing["options"]["consistent_overlap_bins"]
    bad("old_missing.json", old_missing, "options")
    wrong = predictions.load_json(a_json)
    del wrong["sets"][0]["overall"]
    bad("noset.json", wrong, "sets")
    c = predictions.load_json(b_json)
    c["options"]["auc_thresholds_deg"] = [1, 2, 3]
    bad("auc.json", c, "differ", extra=("--eval", a_json))
    r = common.occgt("inspect", "split", split, "--eval", os.path.join(work, "absent.json"),
                     "--out", os.path.join(work, "bad_absent"), check=False)
    assert r.returncode == 1 and "absent.json" in r.stderr, r.stderr
    r = common.occgt("inspect", "split", split, "--eval", a_json, "--eval-gallery", "99",
                     "--out", os.path.join(work, "bad_gallery"), check=False)
    assert r.returncode == 2 and "--eval-gallery" in r.stderr, r.stderr
    print("eval report: ok")


if __name__ == "__main__":
    main()
