"""`occgt eval` end to end on the demo split (docs/EVAL.md): ground-truth matches from the
shards score AUC near 100 and per-type precision/recall 100; matches moved by known pixel
errors give the expected precision; a known extra rotation gives the expected pose error;
every per-pair pose error and the AUCs equal the reference written from GROUND_TRUTH.md §7
(tests/eval/reference.py, cv2); the pair metrics are the samples' under their own names
(consistent_overlap, overlap, occlusion_ratio(_visible)) and binned as documented, with
--overlap-bins the same as --consistent-overlap-bins; rescaled predictions give the same scores; the output is
the same at 1 and 2 threads and valid against schemas/eval.schema.json; each bad
prediction file fails with one clear line and writes nothing; missing pairs are failures."""
import json
import os
import shutil
import stat
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "integration"))
import common  # noqa: E402
import predictions  # noqa: E402
import reference  # noqa: E402


def read_bytes(path):
    with open(path, "rb") as f:
        return f.read()


def run_eval(split, out, *args, check=True):
    return common.occgt("eval", split, "--out", out, *args, check=check)




def main():
    work = common.scratch("eval_cli")
    split = os.path.join(work, "demo")
    common.occgt("build", "--json", os.path.join(common.SOURCE, "recipes", "demo.yaml"), "--out", split)
    samples = list(predictions.iter_samples(split))
    assert len(samples) >= 20, len(samples)
    truth, types, metas = {}, {}, {}
    for s in samples:
        k0, k1, t = predictions.truth_matches(s)
        truth[s["__key__"]] = (k0, k1)
        types[s["__key__"]] = t
        metas[s["__key__"]] = s["json"]
    W, H = samples[0]["json"]["resolution"]

    def save(name, pairs, extra=None):
        arrays = {}
        for key, (k0, k1) in pairs.items():
            arrays[key + "/kpts0"] = np.asarray(k0, np.float32)
            arrays[key + "/kpts1"] = np.asarray(k1, np.float32)
        arrays.update(extra or {})
        path = os.path.join(work, name + ".npz")
        np.savez(path, **arrays)
        return path

    # 1. Ground-truth matches, two estimators, against the reference.
    gt_path = save("gt", truth)
    out = os.path.join(work, "gt.json")
    r = run_eval(split, out, "--predictions", gt_path, "--ransac-px", "0.5,1.0")
    doc = predictions.load_json(out)
    predictions.check_eval_schema(doc, common.SOURCE)
    assert "AUC" in r.stdout and "per-type" in r.stdout, r.stdout
    assert [e["ransac_px"] for e in doc["options"]["estimators"]] == [0.5, 1.0]
    # The summary's occlusion line names the estimator it shows (the first of two) and its
    # bins as they are, half-open but the last, with the edges of eval.json.
    line = next(x for x in r.stdout.splitlines() if " by occlusion (" in x)
    assert f"by occlusion (image, {doc['options']['estimators'][0]['name']}):" in line, line
    bins = [b for b in doc["sets"][0]["by_occlusion"]["image"] if b["pairs"]]
    for b in bins:
        close = "]" if b["hi"] == doc["sets"][0]["by_occlusion"]["image"][-1]["hi"] else ")"
        assert f"[{b['lo']:.4g},{b['hi']:.4g}{close} " in line, (b, line)
    # A bin without pairs has no AUC (it said 0.0, as if scored), no mean; counts are 0.
    empty = [b for b in doc["sets"][0]["by_occlusion"]["image"] if not b["pairs"]]
    assert empty, "the demo fills every occlusion bin: the check proves nothing"
    for b in empty:
        for pose in b["pose"]:
            assert pose["auc_percent"] == [None, None, None], b
            assert pose["mean_error_deg"] is None and pose["failures"] == 0, b
        assert b["matches_mean"] is None and b["epipolar_precision_percent"] is None, b
    overall = doc["sets"][0]["overall"]
    for t in ("vv", "vo", "ov"):
        x = overall["types"][t]
        assert x["predicted"] > 0 and x["precision_percent"] == 100.0, (t, x)
        assert x["recall_percent"] == 100.0, (t, x)
    assert overall["epipolar_precision_percent"] == 100.0, overall
    for e, px in enumerate((0.5, 1.0)):
        ref_errors = []
        for p in doc["pairs"]:
            key = p["key"]
            meta = metas[key]
            K0, K1, T = (np.array(meta[k]) for k in ("K0", "K1", "T_0to1"))
            est = reference.estimate_pose(*truth[key], K0, K1, px, 0.99999)
            ref = np.inf if est is None else reference.pose_error(T, *est)
            got = p["sets"][0]["pose"][e]["error_deg"]
            got = np.inf if got is None else got
            assert (np.isinf(ref) and np.isinf(got)) or abs(ref - got) < 1e-6, (key, px, ref, got)
            eps = reference.epipolar_precision(*truth[key], K0, K1, T, 5e-4)
            assert abs(eps - p["sets"][0]["epipolar_precision"]) < 1e-12
            ref_errors.append(ref)
        ref_auc = [100 * a for a in reference.auc(ref_errors, [5, 10, 20])]
        got_auc = overall["pose"][e]["auc_percent"]
        assert np.allclose(ref_auc, got_auc, atol=1e-6), (ref_auc, got_auc)
        assert got_auc[0] > 90, got_auc  # "near 100" (OpenCV's RANSAC misses one demo pair)
    # The pair metrics under their own names (version 2): each the mean (--aggregate's
    # default) of the sample's two directions; by_consistent_overlap bins pairs[].consistent_overlap.
    assert doc["version"] == 2 and doc["options"]["aggregate"] == "mean", doc["options"]
    for p in doc["pairs"]:
        m = metas[p["key"]]["metrics"]
        mean = lambda name: (m["01"][name] + m["10"][name]) / 2  # noqa: E731
        assert abs(p["consistent_overlap"] - mean("consistent_overlap")) < 1e-12, p["key"]
        assert abs(p["overlap"] - mean("overlap")) < 1e-12, p["key"]
        assert abs(p["occlusion"]["image"] - mean("occlusion_ratio")) < 1e-12, p["key"]
        assert abs(p["occlusion"]["visible"] - mean("occlusion_ratio_visible")) < 1e-12, p["key"]
    edges = doc["options"]["consistent_overlap_bins"]
    assert edges == [0, 0.2, 0.4, 0.6, 0.8, 1], edges
    bins = doc["sets"][0]["by_consistent_overlap"]
    assert [(b["lo"], b["hi"]) for b in bins] == list(zip(edges, edges[1:])), bins
    for i, b in enumerate(bins):
        last = i + 1 == len(bins)
        n = sum(1 for p in doc["pairs"] if b["lo"] <= p["consistent_overlap"] and
                (p["consistent_overlap"] < b["hi"] or (last and p["consistent_overlap"] == b["hi"])))
        assert b["pairs"] == n, (b["lo"], b["hi"], b["pairs"], n)

    # 2. Known pixel errors on the vv and vo matches (ov left out: a moved ov match lands
    #    on another pixel of image 0, whose own label decides its class): even matches moved
    #    by 3 px, odd ones by 20 px, along x in image 1, where their error is measured.
    moved = {}
    expect = {0: [0, 0], 1: [0, 0]}  # type -> [correct, total]
    for key, (k0, k1) in truth.items():
        t = types[key]
        shift = np.where(np.arange(len(t)) % 2 == 0, 3.0, 20.0).astype(np.float32)
        k1 = k1.copy()
        k1[:, 0] += shift
        keep = (t != 2) & (k1[:, 0] < W - 0.5)
        moved[key] = (k0[keep], k1[keep])
        for ty in (0, 1):
            sel = keep & (t == ty)
            expect[ty][0] += int((sel & (shift == 3.0)).sum())
            expect[ty][1] += int(sel.sum())
    moved_path = save("moved", moved)
    out = os.path.join(work, "moved.json")
    run_eval(split, out, "--predictions", moved_path)
    got_types = predictions.load_json(out)["sets"][0]["overall"]["types"]
    vv = got_types["vv"]
    expected = 100.0 * expect[0][0] / expect[0][1]
    for ty, name in ((0, "vv"), (1, "vo")):
        x = got_types[name]
        # A 20 px match can satisfy the 1 -> 0 hypothesis by chance: allow 0.5 points.
        assert abs(x["predicted"] - expect[ty][1]) <= 0.005 * expect[ty][1], (name, x, expect)
        assert abs(x["precision_percent"] - 100.0 * expect[ty][0] / expect[ty][1]) < 0.5, (x, expect)
    run_eval(split, out, "--predictions", moved_path, "--px", "2")
    vv2 = predictions.load_json(out)["sets"][0]["overall"]["types"]["vv"]
    assert vv2["correct"] <= 0.005 * vv2["predicted"], vv2  # 3 px > 2 px: all wrong

    # 3. A known rotation: image 1's points moved by the homography of a camera rotation of
    #    3 degrees about the translation direction: rotation error 3, translation error 0.
    key = next(k for k in truth if len(truth[k][0]) > 200)
    meta = metas[key]
    K1 = np.array(meta["K1"])
    T = np.array(meta["T_0to1"])
    axis = T[:3, 3] / np.linalg.norm(T[:3, 3])
    import cv2
    Rx, _ = cv2.Rodrigues(axis * np.deg2rad(3.0))
    Hm = K1 @ Rx @ np.linalg.inv(K1)
    k0, k1 = truth[key]
    h = np.c_[k1, np.ones(len(k1))] @ Hm.T
    k1r = (h[:, :2] / h[:, 2:]).astype(np.float32)
    inside = (k1r[:, 0] >= 0) & (k1r[:, 0] < W - 1) & (k1r[:, 1] >= 0) & (k1r[:, 1] < H - 1)
    rot_path = save("rotated", {key: (k0[inside], k1r[inside])})
    out = os.path.join(work, "rotated.json")
    r = run_eval(split, out, "--predictions", rot_path)
    assert "have no prediction" in r.stderr, r.stderr  # every other pair is missing
    doc = predictions.load_json(out)
    pair = next(p for p in doc["pairs"] if p["key"] == key)
    pose = pair["sets"][0]["pose"][0]
    assert abs(pose["rotation_deg"] - 3.0) < 0.05 and pose["translation_deg"] < 0.05, pose
    missing = doc["sets"][0]["pairs_missing"]
    assert missing == len(truth) - 1 and doc["sets"][0]["overall"]["pose"][0]["failures"] >= missing
    assert key not in doc["sets"][0]["missing_keys"]

    # 4. Stated resolution: the same points at 2x, with a 'resolution' member.
    scaled = {k: (2 * (a + 0.5) - 0.5, 2 * (b + 0.5) - 0.5) for k, (a, b) in truth.items()}
    sc_path = save("scaled", scaled, {"resolution": np.array([2 * W, 2 * H], np.int32)})
    out = os.path.join(work, "scaled.json")
    run_eval(split, out, "--predictions", sc_path)
    a = predictions.load_json(os.path.join(work, "gt.json"))["sets"][0]["overall"]
    b = predictions.load_json(out)["sets"][0]["overall"]
    assert b["types"]["vv"]["precision_percent"] == 100.0
    assert np.allclose(a["pose"][0]["auc_percent"], b["pose"][0]["auc_percent"], atol=0.5)

    # 4b. A pair predicted without matches: its occluded_share is null (0 / 0; it was 0.0).
    first_key = sorted(truth)[0]
    none_path = save("no_matches", {**truth, first_key: (np.zeros((0, 2)), np.zeros((0, 2)))})
    out = os.path.join(work, "no_matches.json")
    run_eval(split, out, "--predictions", none_path)
    doc = predictions.load_json(out)
    predictions.check_eval_schema(doc, common.SOURCE)
    shares = {p["key"]: p["sets"][0]["occluded_share"] for p in doc["pairs"]}
    assert shares[first_key] is None, shares[first_key]
    assert all(v is not None for k, v in shares.items() if k != first_key), shares

    # 5. Two sets, two estimators: the same bytes at 1 and 2 threads; a folder layout.
    folder = os.path.join(work, "gt_folder")
    for key, (k0, k1) in truth.items():
        os.makedirs(os.path.join(folder, os.path.dirname(key)), exist_ok=True)
        np.savez(os.path.join(folder, key + ".npz"), kpts0=k0, kpts1=k1,
                 confidence=np.ones(len(k0), np.float32))
    outs = []
    for threads in ("1", "2"):
        o = os.path.join(work, f"t{threads}.json")
        run_eval(split, o, "--predictions", "gt=" + gt_path, "--predictions", folder,
                 "--predictions", moved_path, "--ransac-px", "0.5,2", "--threads", threads)
        with open(o, "rb") as f:
            outs.append(f.read())
    assert outs[0] == outs[1], "eval.json differs between --threads 1 and 2"
    doc = json.loads(outs[0])
    predictions.check_eval_schema(doc, common.SOURCE)
    assert [s["name"] for s in doc["sets"]] == ["gt", "gt_folder", "moved"]
    assert doc["sets"][0]["overall"] == doc["sets"][1]["overall"]
    gt_folder = folder

    # 5a. A folder whose scene subfolders are symlinks to folders is read through them (not
    #     skipped); a symlink back to a folder above is one line naming it, nothing written.
    linked = os.path.join(work, "linked_folder")
    os.makedirs(linked)
    for scene in sorted(os.listdir(gt_folder)):
        os.symlink(os.path.join(gt_folder, scene), os.path.join(linked, scene))
    out = os.path.join(work, "linked.json")
    r = run_eval(split, out, "--predictions", "gt=" + linked, "--ransac-px", "0.5,1.0")
    assert "have no prediction" not in r.stderr, r.stderr
    doc = predictions.load_json(out)
    assert doc["sets"][0]["pairs_missing"] == 0 and doc["sets"][0]["layout"] == "folder"
    assert doc["sets"][0]["overall"] == \
        predictions.load_json(os.path.join(work, "gt.json"))["sets"][0]["overall"]
    looped = os.path.join(work, "looped_folder")
    os.makedirs(os.path.join(looped, "sub"))
    first_key = next(iter(truth))
    os.makedirs(os.path.join(looped, os.path.dirname(first_key)))
    np.savez(os.path.join(looped, first_key + ".npz"), kpts0=truth[first_key][0],
             kpts1=truth[first_key][1])
    os.symlink("..", os.path.join(looped, "sub", "up"))
    o = os.path.join(work, "looped.json")
    r = run_eval(split, o, "--predictions", looped, check=False)
    lines = [x for x in r.stderr.splitlines() if x]
    assert r.returncode == 1 and len(lines) == 1, (r.returncode, r.stderr)
    assert lines[0].startswith("occgt: error: " + os.path.join(looped, "sub", "up") + ": ") and \
        "symlink loop" in lines[0], lines
    assert not os.path.exists(o)

    # 5b. Keyed by LoFTR pair names ('#'.join(pair_names) of LoFTR's test loop): the
    #     scene's LoFTR folder (the name itself for ScanNet names, else scene%04d_00 of its
    #     line in loftr/scenes.txt) and the frame numbers of pairs.jsonl; a data-root
    #     prefix and another image extension are accepted. Same scores as by sample key.
    with open(os.path.join(split, "loftr", "scenes.txt")) as f:
        aliases = {name: f"scene{i:04d}_00" for i, name in enumerate(f.read().split())}
    loftr_name = {}
    with open(os.path.join(split, "pairs.jsonl")) as f:
        for line in f:
            p = json.loads(line)
            folder = aliases.get(p["scene"], p["scene"])
            n0, n1 = p["frame0"]["number"], p["frame1"]["number"]
            loftr_name[p["key"]] = f"scans/{folder}/color/{n0}.jpg#{folder}/color/{n1}.png"
    by_name = save("gt_loftr", {loftr_name[k]: v for k, v in truth.items()})
    out = os.path.join(work, "gt_loftr.json")
    run_eval(split, out, "--predictions", "gt=" + by_name, "--ransac-px", "0.5,1.0")
    a, b = predictions.load_json(os.path.join(work, "gt.json")), predictions.load_json(out)
    assert a["sets"][0]["overall"] == b["sets"][0]["overall"]
    assert [p["sets"][0]["pose"][0] for p in a["pairs"]] == \
        [p["sets"][0]["pose"][0] for p in b["pairs"]]
    # The folder layout takes LoFTR pair names too: DIR/<name>.npz, each '/' a subfolder.
    loftr_folder = os.path.join(work, "gt_loftr_folder")
    for key, (k0, k1) in truth.items():
        path = os.path.join(loftr_folder, loftr_name[key] + ".npz")
        os.makedirs(os.path.dirname(path), exist_ok=True)
        np.savez(path, kpts0=k0, kpts1=k1)
    out = os.path.join(work, "gt_loftr_folder.json")
    run_eval(split, out, "--predictions", "gt=" + loftr_folder, "--ransac-px", "0.5,1.0")
    c = predictions.load_json(out)
    assert c["sets"][0]["pairs_missing"] == 0 and a["sets"][0]["overall"] == c["sets"][0]["overall"]

    # 5b'. Keyed by the pair names of occgt's torch datasets ('#'.join(pair_names) of a
    #      LoFTR-style loop over ShardDataset / PairIndexDataset: "<scene>/<id0>#<scene>/<id1>";
    #      tests/python/shard_dataset_test.py checks that the datasets give these names).
    dataset_name = {}
    with open(os.path.join(split, "pairs.jsonl")) as f:
        for line in f:
            p = json.loads(line)
            dataset_name[p["key"]] = (f"{p['scene']}/{p['frame0']['id']}#"
                                      f"{p['scene']}/{p['frame1']['id']}")
    by_dataset = save("gt_dataset_names", {dataset_name[k]: v for k, v in truth.items()})
    out = os.path.join(work, "gt_dataset_names.json")
    run_eval(split, out, "--predictions", "gt=" + by_dataset, "--ransac-px", "0.5,1.0")
    d = predictions.load_json(out)
    assert d["sets"][0]["pairs_missing"] == 0 and a["sets"][0]["overall"] == d["sets"][0]["overall"]

    # 5c. --consistent-overlap-bins, and --overlap-bins (its earlier spelling): the same bytes.
    outs = []
    for flag in ("--consistent-overlap-bins", "--overlap-bins"):
        o = os.path.join(work, "bins" + flag.replace("-", "_") + ".json")
        run_eval(split, o, "--predictions", gt_path, flag, "0,0.5,1")
        with open(o, "rb") as f:
            outs.append(f.read())
    assert outs[0] == outs[1], "--overlap-bins and --consistent-overlap-bins differ"
    d = json.loads(outs[0])
    assert d["options"]["consistent_overlap_bins"] == [0, 0.5, 1]
    assert len(d["sets"][0]["by_consistent_overlap"]) == 2
    assert sum(b["pairs"] for b in d["sets"][0]["by_consistent_overlap"]) == len(truth)

    # 6. Bad prediction files: one line, exit 1, nothing written.
    import re
    first = next(iter(truth))
    scene_, ids_ = first.rsplit("/", 1)
    id0_, id1_ = ids_.split("_")
    reversed_key = f"{scene_}/{id1_}_{id0_}"
    side0, side1 = dataset_name[first].split("#")
    reversed_dataset = f"{side1}#{side0}"
    k0, k1 = truth[first]
    nan = k0.copy()
    nan[3, 1] = np.nan
    bad = {
        "nan": ({first: (nan, k1)}, None, rf"{first}/kpts0: expected finite values"),
        "shape": ({first: (np.c_[k0, k0[:, :1]], k1)}, None, r"kpts0: expected shape \[N, 2\]"),
        "count": ({first: (k0, k1[:-1])}, None, r"kpts1: expected as many points as kpts0"),
        "unknown": ({first: (k0, k1)}, {first + "/scores": np.zeros(3)}, r"scores: unknown member"),
        "extra": ({first: (k0, k1), "nowhere/000000_000001": (k0, k1)}, None,
                  r"pair nowhere/000000_000001 is not a sample of the split"),
        "outside": ({first: (k0 + W, k1)}, None, r"kpts0: point 0 .* is outside the"),
        "loftr_unknown": ({"scene9999_00/color/1.jpg#scene9999_00/color/2.jpg": (k0, k1)}, None,
                          r"\(a LoFTR pair name\) is not a pair of the split"),
        "twice": ({first: (k0, k1), loftr_name[first]: (k0, k1)}, None,
                  rf"pair {first} is given twice"),
        "twice_dataset": ({first: (k0, k1), dataset_name[first]: (k0, k1)}, None,
                          rf"pair {first} is given twice"),
        "dataset_unknown": ({"synth_000/000000#synth_000/999999": (k0, k1)}, None,
                            r"pair synth_000/000000#synth_000/999999 is not a sample of the split"),
        "dtype": ({first: (k0, k1)}, {first + "/confidence": np.ones(len(k0), np.int32)},
                  r"confidence: expected dtype float32"),
        # The pair in the other order: named as such, with the split's name for it.
        "reversed": ({reversed_key: (k1, k0)}, None,
                     rf"pair {re.escape(reversed_key)} is not a sample of the split \(it holds "
                     rf"the pair in the other order, {re.escape(first)}: give it under that "
                     r"name with kpts0 and kpts1 swapped\)"),
        "reversed_dataset": ({reversed_dataset: (k1, k0)}, None,
                             rf"it holds the pair in the other order, "
                             rf"{re.escape(dataset_name[first])}:"),
    }
    import re
    for name, (pairs, extra, pattern) in bad.items():
        path = save("bad_" + name, pairs, extra)
        o = os.path.join(work, f"bad_{name}.json")
        r = run_eval(split, o, "--predictions", path, check=False)
        lines = [x for x in r.stderr.splitlines() if x]
        assert r.returncode == 1 and len(lines) == 1, (name, r.returncode, r.stderr)
        assert lines[0].startswith("occgt: error: ") and re.search(pattern, lines[0]), (name, lines)
        # The documented form "<file>[:<member>]: <problem>", the file first.
        assert lines[0].startswith("occgt: error: " + path + ":"), (name, lines)
        assert not os.path.exists(o) and not os.path.exists(o + ".tmp"), name
    notnpz = os.path.join(work, "bad_notnpz.npz")
    with open(notnpz, "w") as f:
        f.write("not a zip")
    r = run_eval(split, os.path.join(work, "x.json"), "--predictions", notnpz, check=False)
    assert r.returncode == 1 and len(r.stderr.splitlines()) == 1, r.stderr
    assert r.stderr.startswith("occgt: error: " + notnpz + ": "), r.stderr
    # Usage errors: one line naming the flag, exit 2 (every option field a flag sets).
    for args in (["--ransac-px", "abc"], ["--occlusion", "paper"], ["--px", "-1"],
                 ["--min-confidence", "-1"], ["--min-confidence", "nan"],
                 ["--occlusion", "image,image"], ["--failure-error", "200"],
                 ["--curve-step", "0"], ["--auc", "10,5"], ["--epipolar-threshold", "0"],
                 ["--occlusion-bins", "0.5,0.1"], ["--overlap-bins", "0"],
                 ["--consistent-overlap-bins", "0"], ["--consistent-overlap-bins", "0.5,x"],
                 ["--overlap-bins", "0.5,x"],
                 ["--ransac-conf", "1"], ["--ransac-iters", "0"], ["--ransac-px", "0"],
                 # Found by a probe of ~300 inputs: an empty value (--failure-error '' was 0
                 # and changed the results), an empty item or a trailing comma (dropped), an
                 # item twice (two identical estimator settings), a curve of 10^9 points (out
                 # of memory), an AUC beyond the largest pose error.
                 ["--failure-error", ""], ["--min-confidence", ""], ["--protocol", ""],
                 ["--occlusion-bins", ""], ["--threads", ""], ["--auc", "5,10,"],
                 ["--auc", "5,,10"], ["--occlusion", "image,"], ["--estimator", "ransac,"],
                 ["--ransac-px", "0.5,0.5"], ["--estimator", "ransac,ransac"],
                 ["--curve-step", "1e-9"], ["--auc", "5,200"],
                 # Not decimal numbers (std::stod took them: 0x10 was 16, " 5" was 5).
                 ["--auc", "0x10"], ["--auc", " 5"], ["--ransac-px", "0.5,inf"],
                 ["--occlusion-bins", "nan"],
                 # A --predictions without a path, or a set name that is blank or breaks the
                 # summary's lines.
                 ["--predictions", "foo="], ["--predictions", " =" + gt_path],
                 ["--predictions", "a\nb=" + gt_path]):
        r = run_eval(split, os.path.join(work, "x.json"), "--predictions", gt_path, *args,
                     check=False)
        assert r.returncode == 2 and len(r.stderr.splitlines()) == 1, (args, r.returncode, r.stderr)
        assert r.stderr.startswith("occgt: error: " + args[0] + ": "), (args, r.stderr)
        assert not os.path.exists(os.path.join(work, "x.json")), args
    # Several problems: each listed, the first 20 of a folder of 25 foreign files, then
    # the count.
    foreign = os.path.join(work, "foreign")
    os.makedirs(foreign, exist_ok=True)
    for i in range(25):
        shutil.copyfile(gt_path, os.path.join(foreign, f"x{i:02d}.npz"))
    r = run_eval(split, os.path.join(work, "x.json"), "--predictions", foreign, check=False)
    lines = r.stderr.splitlines()
    assert r.returncode == 1 and len(lines) == 21, (r.returncode, lines[:3], len(lines))
    assert all(x.startswith(f"occgt: error: {foreign}/x") for x in lines[:20]), lines[:3]
    assert lines[20] == ("occgt: error: predictions: 25 problems (the first 20 listed above); "
                         "nothing written"), lines[20]
    assert not os.path.exists(os.path.join(work, "x.json"))
    # Which name is at fault: a path given twice names its set; ".NPZ" in any case is
    # dropped from a set's name.
    r = run_eval(split, os.path.join(work, "x.json"), "--predictions", gt_path, "--predictions",
                 gt_path, check=False)
    name = os.path.basename(gt_path)[:-4]
    assert r.returncode == 2 and r.stderr == (
        f"occgt: error: --predictions: '{gt_path}': the set name '{name}' is given twice (use "
        "NAME=PATH to tell the sets apart)\n"), r.stderr
    upper = os.path.join(work, "SET.NPZ")
    shutil.copyfile(gt_path, upper)
    run_eval(split, os.path.join(work, "upper.json"), "--predictions", upper)
    with open(os.path.join(work, "upper.json")) as f:
        assert [x["name"] for x in json.load(f)["sets"]] == ["SET"]
    # --out: checked before any work. Not a folder, a device or an input of the run (each was
    # replaced by eval.json, or failed after the whole evaluation); a link is written through.
    victim = os.path.join(work, "victim.npz")
    shutil.copyfile(gt_path, victim)
    fifo = os.path.join(work, "fifo")
    if not os.path.exists(fifo):
        os.mkfifo(fifo)
    for out, message in [(work, "is a folder"), (work + "/new/", "names a folder"),
                         ("/dev/null", "exists and is not a regular file"), (fifo, "exists and "
                                                                              "is not a regular"),
                         (victim, "an input of this run"),
                         (os.path.join(split, "index.json"), "an input of this run"), ("", "")]:
        before = {p: read_bytes(p) for p in (victim, os.path.join(split, "index.json"))}
        r = run_eval(split, out, "--predictions", victim, check=False)
        assert r.returncode == 2 and len(r.stderr.splitlines()) == 1, (out, r.returncode, r.stderr)
        assert r.stderr.startswith("occgt: error: --out: ") and message in r.stderr, r.stderr
        assert all(read_bytes(p) == b for p, b in before.items()), out
    assert stat.S_ISCHR(os.stat("/dev/null").st_mode) and stat.S_ISFIFO(os.stat(fifo).st_mode)
    assert not os.path.exists(work + "/new")
    target = os.path.join(work, "target.json")
    link = os.path.join(work, "link.json")
    for p in (target, link):
        if os.path.lexists(p):
            os.remove(p)
    with open(target, "w") as f:
        f.write("old")
    os.symlink(target, link)
    run_eval(split, link, "--predictions", gt_path)
    assert os.path.islink(link) and json.loads(read_bytes(target))["sets"], target
    # A damaged split is named, not blamed on the predictions: pairs.jsonl without a line,
    # index.json counting a sample its shard does not hold.
    damaged = os.path.join(work, "damaged")
    shutil.rmtree(damaged, ignore_errors=True)
    shutil.copytree(split, damaged)
    with open(os.path.join(damaged, "pairs.jsonl")) as f:
        lines = f.readlines()
    with open(os.path.join(damaged, "pairs.jsonl"), "w") as f:
        f.writelines(lines[1:])
    r = run_eval(damaged, os.path.join(work, "x.json"), "--predictions", gt_path, check=False)
    assert r.returncode == 1 and len(r.stderr.splitlines()) == 1, r.stderr
    assert f"pairs.jsonl: {len(lines) - 1} sample lines, " in r.stderr, r.stderr
    with open(os.path.join(damaged, "pairs.jsonl"), "w") as f:
        f.writelines(lines)
    with open(os.path.join(damaged, "index.json")) as f:
        index = json.load(f)
    index["shardlist"][0]["nsamples"] += 1
    with open(os.path.join(damaged, "pairs.jsonl"), "a") as f:
        f.write(lines[0].replace(json.loads(lines[0])["key"], "synth_009/000000_000001"))
    with open(os.path.join(damaged, "index.json"), "w") as f:
        json.dump(index, f)
    r = run_eval(damaged, os.path.join(work, "x.json"), "--predictions", gt_path, check=False)
    errors = [x for x in r.stderr.splitlines() if x.startswith("occgt: error: ")]
    assert r.returncode == 1 and len(errors) == 1, r.stderr  # after the missing pair's warning
    assert "000000.tar: holds " in errors[0] and "samples, index.json says" in errors[0], r.stderr
    # Both spellings of the consistent_overlap bins at once: a usage error naming both.
    r = run_eval(split, os.path.join(work, "x.json"), "--predictions", gt_path, "--overlap-bins",
                 "0,1", "--consistent-overlap-bins", "0,1", check=False)
    assert r.returncode == 2 and len(r.stderr.splitlines()) == 1, (r.returncode, r.stderr)
    assert "--overlap-bins" in r.stderr and "--consistent-overlap-bins" in r.stderr, r.stderr
    print(f"eval cli: {len(truth)} pairs, AUC@5 of the ground truth {got_auc[0]:.2f}, "
          f"moved vv precision {vv['precision_percent']:.2f} (expected {expected:.2f})")


if __name__ == "__main__":
    main()
