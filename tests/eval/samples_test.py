"""`occgt eval` on the real samples (../shared/data, read in place through the shipped
recipes sevenscenes-sample and tartanair-sample): ground-truth matches from the shards
score per-type precision and recall 100 and AUC@5 > 95; the SIFT baseline
(scripts/eval_sift_baseline.py) runs, and its vv precision equals an independent NumPy
count (l0 VISIBLE, the keypoint unprojected with the depth of its nearest pixel, warped
with T_0to1, within 8 px) up to the few matches the ov rule reclassifies."""
import os
import subprocess
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "integration"))
import common  # noqa: E402
import predictions  # noqa: E402


def numpy_vv(samples, pred):
    correct = total = 0
    for s in samples:
        m, key = s["json"], s["__key__"]
        W, H = m["resolution"]
        K0, K1, T = (np.array(m[k]) for k in ("K0", "K1", "T_0to1"))
        k0 = pred[key + "/kpts0"].astype(float)
        k1 = pred[key + "/kpts1"].astype(float)
        u = np.clip(np.rint(k0[:, 0]).astype(int), 0, W - 1)
        v = np.clip(np.rint(k0[:, 1]).astype(int), 0, H - 1)
        vis = s["label01.npy"][v, u] == 2
        d = s["depth0.npy"][v, u]
        p = np.stack([(k0[:, 0] - K0[0, 2]) / K0[0, 0] * d, (k0[:, 1] - K0[1, 2]) / K0[1, 1] * d, d], 1)
        q = p @ T[:3, :3].T + T[:3, 3]
        x = np.stack([K1[0, 0] * q[:, 0] / q[:, 2] + K1[0, 2], K1[1, 1] * q[:, 1] / q[:, 2] + K1[1, 2]], 1)
        err = np.linalg.norm(x - k1, axis=1)
        correct += int((vis & (err <= 8)).sum())
        total += int(vis.sum())
    return correct, total


def main():
    common.shared("sevenscenes")
    common.shared("tartanair")
    work = common.scratch("eval_samples")
    for recipe in ("sevenscenes-sample", "tartanair-sample"):
        split = os.path.join(work, recipe)
        common.occgt("build", os.path.join(common.SOURCE, "recipes", recipe + ".yaml"), "--out", split)
        samples = list(predictions.iter_samples(split))
        arrays = {}
        for s in samples:
            k0, k1, _ = predictions.truth_matches(s)
            arrays[s["__key__"] + "/kpts0"], arrays[s["__key__"] + "/kpts1"] = k0, k1
        gt = os.path.join(work, recipe + "_gt.npz")
        np.savez(gt, **arrays)
        sift = os.path.join(work, recipe + "_sift.npz")
        subprocess.run(["/usr/bin/python3", os.path.join(common.SOURCE, "scripts", "eval_sift_baseline.py"),
                        split, sift], check=True, capture_output=True)
        out = os.path.join(work, recipe + ".json")
        common.occgt("eval", split, "--predictions", "gt=" + gt, "--predictions", "sift=" + sift,
                     "--out", out)
        import json
        with open(out) as f:
            doc = json.load(f)
        g = doc["sets"][0]["overall"]
        for t in ("vv", "vo", "ov"):
            x = g["types"][t]
            assert x["truth"] == 0 or (x["precision_percent"] == 100 and x["recall_percent"] == 100), (recipe, t, x)
        assert g["pose"][0]["auc_percent"][0] > 95, (recipe, g["pose"])
        vv = doc["sets"][1]["overall"]["types"]["vv"]
        correct, total = numpy_vv(samples, np.load(sift))
        assert total > 100, (recipe, total)
        assert abs(vv["predicted"] - total) <= 0.01 * total, (recipe, vv, total)
        assert abs(vv["correct"] - correct) <= 0.01 * total, (recipe, vv, correct)
        print(f"{recipe}: {len(samples)} pairs, ground truth AUC@5 {g['pose'][0]['auc_percent'][0]:.2f}; "
              f"SIFT vv precision {vv['precision_percent']:.1f} (NumPy {100 * correct / total:.1f})")
    check_damaged_labels(os.path.join(work, "tartanair-sample"), gt)


def check_damaged_labels(split, gt):
    """A label code 9 in a sample's label01 (index.json's size and MD5 updated) stops eval
    with one line naming the member (shards::CheckPairSampleValues); it used to be scored."""
    import io
    import json
    import shutil

    damaged = split + "_damaged_labels"
    shutil.rmtree(damaged, ignore_errors=True)
    shutil.copytree(split, damaged)
    with open(os.path.join(damaged, "index.json")) as f:
        tar_path = os.path.join(damaged, json.load(f)["shardlist"][0]["url"])

    def label_9(plain):
        labels = np.load(io.BytesIO(plain))
        labels[2, 3] = 9
        b = io.BytesIO()
        np.save(b, labels)
        return b.getvalue()

    key = common.edit_first_sample_member(tar_path, "label01.npy", label_9)
    out_json = damaged + ".json"
    r = common.occgt("eval", damaged, "--predictions", "gt=" + gt, "--out", out_json, check=False)
    want = (f"occgt: error: eval: {tar_path}:{key}.label01.npy: pixel (3, 2) holds 9; "
            f"expected a label code 0..5")
    assert r.returncode == 1 and r.stderr.strip() == want, (r.returncode, r.stderr)
    assert not os.path.exists(out_json)


if __name__ == "__main__":
    main()
