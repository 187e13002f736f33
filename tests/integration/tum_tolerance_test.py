"""The TUM association tolerance reaches every command (docs/DATASETS.md "TUM"): a recipe's
dataset.tum_max_dt_s, `--tum-max-dt` of scan, pair, occupancy and inspect pair. On a sequence
whose groundtruth lies 0.03 s from every other depth frame, the default 0.02 s leaves those
frames without a pose, 0.05 s gives them one: scan, pair and build agree (`occgt scan
--tum-max-dt` alone could widen it, so the scan and the build disagreed)."""
import json
import os
import sys

sys.path.insert(0, os.path.dirname(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "support"))
import common  # noqa: E402
from tum_sequence import make_sequence  # noqa: E402


def main():
    root = common.scratch("tum_tolerance")
    seq = make_sequence(root)
    usable = {}
    for extra in ([], ["--tum-max-dt", "0.05"]):
        doc = json.loads(common.occgt("scan", seq, "--format", "tum", "--json", *extra).stdout)
        usable[tuple(extra)] = doc["totals"]["usable"]
    assert usable == {(): 4, ("--tum-max-dt", "0.05"): 8}, usable

    # pair (and occupancy, inspect pair: the same flags) on an odd frame.
    frames = ["--scene", "", "--frames", "100.000000,100.100000"]
    out = os.path.join(root, "pair")
    r = common.occgt("pair", "--root", seq, "--format", "tum", *frames, "--out", out,
                     check=False)
    assert r.returncode == 2 and "pose: no groundtruth within 0.02s" in r.stderr, r.stderr
    common.occgt("pair", "--root", seq, "--format", "tum", *frames, "--tum-max-dt", "0.05",
                 "--out", out)
    assert os.path.isfile(os.path.join(out, "label01.npy"))
    # meta.json records the tolerance, so `inspect pair --pair-dir` opens the colour images
    # the pair's frames had: with the odd frames' images 0.03 s away, the default found none
    # for frame 100.1 ("missing field image1.png").
    with open(os.path.join(out, "meta.json")) as f:
        assert json.load(f)["tum_max_dt_s"] == 0.05
    with open(os.path.join(seq, "rgb.txt")) as f:
        rgb = f.read()
    with open(os.path.join(seq, "rgb.txt"), "w") as f:
        f.write(rgb.replace("100.100000 rgb/", "100.130000 rgb/"))
    pics = os.path.join(root, "pics")
    common.occgt("inspect", "pair", "--pair-dir", out, "--root", seq, "--out", pics)
    assert os.path.isfile(os.path.join(pics, "labels.png")), os.listdir(pics)
    with open(os.path.join(seq, "rgb.txt"), "w") as f:
        f.write(rgb)
    r = common.occgt("pair", "--root", seq, "--format", "generic", *frames, "--tum-max-dt",
                     "0.05", "--out", out, check=False)
    assert r.returncode == 2 and r.stderr.startswith("occgt: error: --tum-max-dt: only for the "
                                                     "tum format"), r.stderr

    # A recipe's dataset.tum_max_dt_s: the build keeps the frames scan --tum-max-dt keeps,
    # and `occgt pair --recipe` reads the same tolerance; recipe.json records it.
    kept = {}
    for dt in (None, 0.05):
        recipe = os.path.join(root, f"r{dt}.yaml")
        with open(recipe, "w") as f:
            f.write("name: tum-tolerance\nresolution: [160, 120]\n"
                    f"dataset: {{format: tum, root: {seq}, min_valid_depth_fraction: 0.1"
                    + ("" if dt is None else f", tum_max_dt_s: {dt}") + "}\n"
                    "occupancy: {enabled: false}\nsample: {image: png}\n")
        s = json.loads(common.occgt("build", "--json", recipe, "--out",
                                    os.path.join(root, f"b{dt}"), "--dry-run").stdout)
        kept[dt] = s["counts"]["frames_kept"]
        if dt is not None:
            common.occgt("pair", "--recipe", recipe, *frames, "--out",
                         os.path.join(root, "pair_recipe"))
            built = os.path.join(root, "built")
            common.occgt("build", recipe, "--out", built)
            with open(os.path.join(built, "recipe.json")) as f:
                assert json.load(f)["dataset"]["tum_max_dt_s"] == 0.05
    assert kept == {None: 4, 0.05: 8}, kept
    bad = os.path.join(root, "bad.yaml")
    with open(bad, "w") as f:
        f.write(f"name: x\ndataset: {{format: generic, root: {seq}, tum_max_dt_s: 0.05}}\n")
    r = common.occgt("build", bad, "--out", os.path.join(root, "bad"), check=False)
    assert r.returncode == 1 and "dataset.tum_max_dt_s: expected only with format tum" in \
        r.stderr, r.stderr
    print("tum_tolerance: ok")


if __name__ == "__main__":
    main()
