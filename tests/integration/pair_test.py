"""occgt pair on real samples, read back the way a trainer would (numpy + jsonschema)."""
import json
import os
import sys

import jsonschema
import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
import common  # noqa: E402

VIS, OCC = 2, 3


def load(out):
    arrays = {n: np.load(os.path.join(out, n + ".npy")) for n in
              ["label01", "label10", "matches", "match_type", "match_xy", "cells0", "cells1"]}
    with open(os.path.join(out, "meta.json")) as f:
        meta = json.load(f)
    return arrays, meta


def check(out, stride=8):
    a, meta = load(out)
    with open(os.path.join(common.SOURCE, "schemas", "pair_meta.schema.json")) as f:
        schema = json.load(f)
    jsonschema.Draft202012Validator.check_schema(schema)
    jsonschema.Draft202012Validator(schema).validate(meta)
    w, h = meta["resolution"]
    for name in ["label01", "label10"]:
        assert a[name].dtype == np.uint8 and a[name].shape == (h, w), (name, a[name].shape)
        assert a[name].max() <= 5
    m = a["match_type"].shape[0]
    assert a["matches"].dtype == np.int32 and a["matches"].shape == (m, 2)
    assert a["match_type"].dtype == np.uint8 and set(np.unique(a["match_type"])) <= {0, 1, 2}
    assert a["match_xy"].dtype == np.float32 and a["match_xy"].shape == (m, 2)
    assert a["cells0"].dtype == np.uint8 and a["cells0"].shape == (h // stride, w // stride)
    assert a["cells1"].shape == (h // stride, w // stride)
    assert m > 0 and np.all(np.isfinite(a["match_xy"]))
    # Counts in meta.json agree with the label arrays.
    names = ["NO_DEPTH", "OUT_OF_VIEW", "VISIBLE", "OCCLUDED", "INCONSISTENT", "UNKNOWN"]
    for lab, key in [("label01", "01"), ("label10", "10")]:
        counts = np.bincount(a[lab].ravel(), minlength=6)
        for k, n in enumerate(names):
            assert counts[k] == meta["metrics"][key]["counts"][n], (lab, n, counts[k])
        assert meta["metrics"][key]["sampled"] == w * h
        assert abs(meta["metrics"][key]["occlusion_ratio"] - counts[OCC] / (w * h)) < 1e-12
    # Matches agree with the cell maps and the type counts.
    cells0, cells1 = a["cells0"].ravel(), a["cells1"].ravel()
    t = a["match_type"]
    i, j = a["matches"][:, 0], a["matches"][:, 1]
    assert np.all((i >= 0) & (i < cells0.size) & (j >= 0) & (j < cells1.size))
    assert np.all(cells0[i[t == 0]] == VIS) and np.all(cells1[j[t == 0]] == VIS)
    assert np.all(cells0[i[t == 1]] == OCC) and np.all(cells1[j[t == 2]] == OCC)
    assert meta["matches"] == {"total": m, "vv": int((t == 0).sum()), "vo": int((t == 1).sum()),
                               "ov": int((t == 2).sum())}
    # vv/vo: match_xy lies in the target cell of image 1 (centre anchors); ov: in image 0's.
    gw = w // stride
    cell_of = lambda xy: (np.floor((xy[:, 1] + 0.5) / stride) * gw +
                          np.floor((xy[:, 0] + 0.5) / stride)).astype(np.int64)
    xy = a["match_xy"].astype(np.float64)
    assert np.all(cell_of(xy[t != 2]) == j[t != 2])
    assert np.all(cell_of(xy[t == 2]) == i[t == 2])
    # Cell maps are the labels at the centre anchors.
    assert np.array_equal(a["cells0"], a["label01"][stride // 2::stride, stride // 2::stride][
        : h // stride, : w // stride])
    return a, meta


def main():
    root7 = common.shared("sevenscenes")
    out = common.scratch("pair_7s")
    common.occgt("pair", "--root", root7, "--format", "sevenscenes", "--scene", "rgbd-frames",
                 "--frames", "000150,000190", "--out", out)
    a, meta = check(out)
    assert 0.2 < meta["metrics"]["01"]["overlap"] <= 1
    assert meta["label_options"]["min_depth_m"] == 0.1  # the dataset's range

    # The compat preset reproduces the release: missing target depth counts as occluded.
    out_c = common.scratch("pair_7s_compat")
    common.occgt("pair", "--root", root7, "--format", "sevenscenes", "--scene", "rgbd-frames",
                 "--frames", "000150,000190", "--preset", "occ2net-compat", "--out", out_c)
    ac, mc = check(out_c)
    assert mc["metrics"]["01"]["counts"]["UNKNOWN"] == 0
    assert mc["metrics"]["01"]["counts"]["OCCLUDED"] > meta["metrics"]["01"]["counts"]["OCCLUDED"]

    # Determinism: same inputs, byte-identical outputs.
    out_again = common.scratch("pair_7s_again")
    common.occgt("pair", "--root", root7, "--format", "sevenscenes", "--scene", "rgbd-frames",
                 "--frames", "000150,000190", "--out", out_again)
    for name in sorted(os.listdir(out)):
        with open(os.path.join(out, name), "rb") as f1, open(os.path.join(out_again, name), "rb") as f2:
            assert f1.read() == f2.read(), name

    # A re-run of other frames into the folder that stops among its arrays (here: matches.npy
    # cannot be written, a folder is in its way; a kill does the same) leaves no meta.json
    # naming the earlier pair beside this pair's label maps, and `inspect pair` refuses the
    # folder (it drew the new arrays over the old pair's images, exit 0). The same for
    # `occgt occupancy` and occupancy.json.
    mixed = common.scratch("pair_7s_mixed")
    args = ["--root", root7, "--format", "sevenscenes", "--scene", "rgbd-frames", "--out", mixed]
    common.occgt("pair", *args, "--frames", "000150,000190")
    common.occgt("occupancy", *args, "--frames", "000150,000190")
    os.remove(os.path.join(mixed, "matches.npy"))
    os.mkdir(os.path.join(mixed, "matches.npy"))
    r = common.occgt("pair", *args, "--frames", "000160,000170", check=False)
    assert r.returncode != 0 and "matches.npy" in r.stderr, (r.returncode, r.stderr)
    assert not os.path.exists(os.path.join(mixed, "meta.json")), os.listdir(mixed)
    os.rmdir(os.path.join(mixed, "matches.npy"))
    os.mkdir(os.path.join(mixed, "occ1.npy.tmp"))  # in the way of occ1.npy's temporary
    r = common.occgt("occupancy", *args, "--frames", "000160,000170", check=False)
    assert r.returncode != 0, r.stderr
    assert not os.path.exists(os.path.join(mixed, "occupancy.json")), os.listdir(mixed)
    os.rmdir(os.path.join(mixed, "occ1.npy.tmp"))
    r = common.occgt("inspect", "pair", "--pair-dir", mixed, "--out", common.scratch("pair_mixed_pic"),
                     check=False)
    assert r.returncode == 1 and "meta.json: missing, while the folder holds label01.npy: an " \
        "`occgt pair` run into it did not finish (re-run it)" in r.stderr, r.stderr
    common.occgt("pair", *args, "--frames", "000160,000170")
    r = common.occgt("inspect", "pair", "--pair-dir", mixed, "--out", common.scratch("pair_mixed_pic"),
                     check=False)
    assert r.returncode == 1 and "occupancy.json: missing, while the folder holds occ0.npy" \
        in r.stderr, r.stderr

    # TartanAir at another resolution and stride, corner anchors.
    roott = common.shared("tartanair/hospital_sample")
    out_t = common.scratch("pair_ta")
    common.occgt("pair", "--root", roott, "--format", "tartanair", "--scene", "hospital_sample",
                 "--frames", "000000,000020", "--resolution", "320x240", "--stride", "16",
                 "--out", out_t)
    _, mt = check(out_t, stride=16)
    assert mt["resolution"] == [320, 240]
    # No upper depth limit: JSON has no infinity, so max_depth_m is null (the schema says so).
    out_inf = common.scratch("pair_inf")
    common.occgt("pair", "--root", roott, "--format", "tartanair", "--scene", "hospital_sample",
                 "--frames", "000000,000020", "--resolution", "320x240", "--max-depth-m", "inf",
                 "--out", out_inf)
    _, mi = check(out_inf)
    assert mi["label_options"]["max_depth_m"] is None, mi["label_options"]

    # Usage errors (docs/CLI.md): one `occgt: error: --flag` line, exit 2, nothing written.
    out_bad = common.scratch("pair_bad")
    r = common.occgt("pair", "--root", root7, "--format", "sevenscenes", "--scene", "rgbd-frames",
                     "--frames", "000150,123456", "--out", out_bad, check=False)
    assert r.returncode == 2 and r.stderr.startswith("occgt: error: --frames: "), r.stderr
    assert r.stderr.count("\n") == 1, r.stderr
    assert os.listdir(out_bad) == []
    r = common.occgt("pair", "--root", root7, "--format", "sevenscenes", "--scene", "rgbd-frames",
                     "--frames", "000150,000190", "--preset", "nope", "--out", out_bad, check=False)
    assert r.returncode == 2 and r.stderr.startswith("occgt: error: --preset: "), r.stderr
    # A frame number given for TartanAir's zero-padded id names the id.
    r = common.occgt("pair", "--root", roott, "--format", "tartanair", "--scene", "hospital_sample",
                     "--frames", "0,20", "--out", out_bad, check=False)
    assert r.returncode == 2 and "(did you mean '000000'?)" in r.stderr, r.stderr
    assert os.listdir(out_bad) == []
    print("1 passed, 0 failed")


if __name__ == "__main__":
    main()
