"""occgt inspect pair / split, read back the way a person would look at them.

- `occgt build recipes/demo.yaml`, then `inspect split` on it: the plots decode with the
  expected sizes and are not blank; report.html opens in headless Chromium from disk,
  every <img> decodes (the page records it in <body data-images-decoded="k/n">), the
  screenshot is not blank, and there is no console error.
- `inspect pair --shard/--key`: PNG sizes follow the working resolution; label overlay
  pixels equal the blend of image0 and the documented label colour (computed here from
  the shard's own label01.npy and image0.png); yellow appears iff the sample has vo
  matches.
- `inspect pair --root ... --frames` on the real TartanAir sample and `inspect split` on a
  folder written by this test (an empty split, a malformed line).
"""
import fcntl
import glob
import gzip
import io
import json
import os
import re
import shutil
import subprocess
import sys
import tarfile

import jsonschema
import numpy as np
from PIL import Image

sys.path.insert(0, os.path.dirname(__file__))
import common  # noqa: E402

# Documented colours (docs/INSPECT.md), (R, G, B).
LABEL_RGB = [(40, 40, 40), (60, 110, 255), (0, 200, 70), (235, 30, 30), (230, 0, 230), (255, 170, 0)]
VO_RGB = (255, 220, 0)
PANEL_GAP = 8
ALPHA = 0.55

failures = []


def html_escape(t):
    return t.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;").replace('"', "&quot;")


def check(cond, msg):
    if not cond:
        failures.append(msg)
        print("FAIL:", msg)


def png(path):
    with open(path, "rb") as f:
        data = f.read()
    check(data[:8] == b"\x89PNG\r\n\x1a\n", f"{path}: PNG signature")
    return np.asarray(Image.open(io.BytesIO(data)).convert("RGB"))


def not_blank(img, name):
    colours = len(np.unique(img.reshape(-1, 3), axis=0))
    check(colours >= 8, f"{name}: only {colours} distinct colours (blank?)")
    check(img.std() > 5, f"{name}: nearly uniform (std {img.std():.2f})")


def read_sample(tar_path, key):
    fields = {}
    with tarfile.open(tar_path) as tf:
        for m in tf.getmembers():
            base = m.name.rsplit("/", 1)
            k = m.name[: len(m.name) - len(base[-1])] + base[-1].split(".", 1)[0]
            if k == key:
                field, data = base[-1].split(".", 1)[1], tf.extractfile(m).read()
                if field.endswith(".gz"):  # sample.compression: deflate (the default)
                    field, data = field[:-3], gzip.decompress(data)
                fields[field] = data
    return fields


def old_style_sample_json(meta):
    """A sample json as occgt wrote it before its occupancy keys took occupancy.json's names:
    "occupancy"."bin_edges_m" and "voxel_m", "occupancy_options"."fusion"."voxel_size_m"."""
    occ, fusion = meta["occupancy"], meta["occupancy_options"]["fusion"]
    occ["bin_edges_m"] = occ.pop("bins")["edges_m"]
    occ["voxel_m"] = fusion["voxel_m"]
    fusion["voxel_size_m"] = fusion.pop("voxel_m")
    return meta


def chromium_check(html, tmp):
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    if chromium is None:
        check(False, "chromium not installed (scripts/setup.sh --test installs it)")
        return
    base = [chromium, "--headless", "--no-sandbox", "--disable-gpu",
            "--disable-background-networking", "--disable-component-update", "--disable-sync",
            "--no-first-run", "--enable-logging=stderr", "--v=0"]
    url = "file://" + os.path.abspath(html)
    r = subprocess.run(base + [f"--user-data-dir={tmp}/profile1", "--dump-dom", url],
                       capture_output=True, text=True, timeout=300)
    dom = r.stdout
    with open(html, encoding="utf-8") as f:
        n_img = len(re.findall(r"<img ", f.read()))
    m = re.search(r'data-images-decoded="(\d+)/(\d+)"', dom)
    check(m is not None, f"report.html: no data-images-decoded in the DOM ({dom[:200]!r})")
    if m:
        check(m.group(1) == m.group(2) == str(n_img),
              f"report.html: {m.group(1)}/{m.group(2)} images decoded, page has {n_img}")
    check(n_img >= 5, f"report.html: only {n_img} images")
    errors = [l for l in r.stderr.splitlines() if "Uncaught" in l or "ERROR:CONSOLE" in l]
    check(not errors, f"report.html: console errors {errors[:3]}")
    shot = os.path.join(tmp, "shot.png")
    subprocess.run(base + [f"--user-data-dir={tmp}/profile2", f"--screenshot={shot}",
                           "--window-size=1280,2000", url],
                   capture_output=True, text=True, timeout=300)
    check(os.path.exists(shot), "chromium wrote no screenshot")
    if os.path.exists(shot):
        img = png(shot)
        check(img.shape[:2] == (2000, 1280), f"screenshot size {img.shape}")
        not_blank(img, "report screenshot")


def main():
    tmp = common.scratch("inspect")
    build = os.path.join(tmp, "demo")
    common.occgt("build", "--json", os.path.join(common.SOURCE, "recipes", "demo.yaml"), "--out", build)

    # --- split report on a real build.
    report = os.path.join(tmp, "report")
    common.occgt("inspect", "split", build, "--out", report, "--gallery", "3")
    for name in ["overlap_hist.png", "occlusion_hist.png", "occlusion_cumulative.png",
                 "overlap_vs_occlusion.png", "pairs_per_scene.png"]:
        img = png(os.path.join(report, name))
        check(img.shape == (480, 800, 3), f"{name}: size {img.shape}")
        not_blank(img, name)
    html = os.path.join(report, "report.html")
    text = open(html, encoding="utf-8").read()
    check("http://" not in text and "https://" not in text, "report.html refers to the network")
    check("@media print" in text, "report.html has no print stylesheet")
    check(text.count("data:image/jpeg;base64,") >= 3 * 2, "gallery images missing")
    # Alt texts: a gallery image names its pair, a plot what it shows (they were "labels",
    # "overlap_hist.png").
    gallery_alts = re.findall(r'<img alt="([^"]+) \(overlap [0-9.]+, occlusion [0-9.]+\): ', text)
    check(len(gallery_alts) >= 3 * 2, f"gallery alt texts without the pair key: {gallery_alts}")
    check('<img alt="Histogram of the selected pairs&#39; overlap"' in text or
          "<img alt=\"Histogram of the selected pairs' overlap\"" in text,
          "overlap_hist.png's alt text")
    # The visible overlap of the weaker direction (selection.visible_overlap's default
    # aggregate), from pairs.jsonl: its min, median, max.
    row = re.search(r"<tr><td>consistent_overlap_min \(visible overlap, weaker direction\)</td>" +
                    r"<td class=\"n\">([^<]*)</td>" * 4, text)
    check(row is not None, "report has no visible overlap row")
    if row:
        with open(os.path.join(build, "pairs.jsonl")) as f:
            weaker = sorted(min(p["metrics"]["01"]["consistent_overlap"],
                                p["metrics"]["10"]["consistent_overlap"])
                            for p in map(json.loads, f))
        lo, med, mean, hi = (float(v) for v in row.groups())
        check(abs(lo - weaker[0]) < 1e-3 and abs(hi - weaker[-1]) < 1e-3,
              f"visible overlap range {lo}..{hi}, expected {weaker[0]}..{weaker[-1]}")
        check(abs(mean - sum(weaker) / len(weaker)) < 1e-3, f"visible overlap mean {mean}")
    # report.json names it as the pair metrics do: consistent_overlap_min, full precision.
    with open(os.path.join(build, "pairs.jsonl")) as f:
        weaker = sorted(min(p["metrics"]["01"]["consistent_overlap"],
                            p["metrics"]["10"]["consistent_overlap"]) for p in map(json.loads, f))
    with open(os.path.join(report, "report.json")) as f:
        pairs_json = json.load(f)["pairs"]
    vmin = pairs_json.get("consistent_overlap_min") or {}
    check("visible_overlap_min" not in pairs_json, "report.json still has visible_overlap_min")
    # The occlusion metric in the recipe's word, beside the field it reads.
    check((pairs_json.get("occlusion_metric"), pairs_json.get("occlusion_field")) ==
          ("image", "occlusion_ratio"),
          f"report.json occlusion_metric/field {pairs_json.get('occlusion_metric')}, "
          f"{pairs_json.get('occlusion_field')}")
    check(vmin.get("min") is not None and abs(vmin["min"] - weaker[0]) < 1e-12 and
          abs(vmin["max"] - weaker[-1]) < 1e-12 and
          abs(vmin["mean"] - sum(weaker) / len(weaker)) < 1e-9,
          f"report.json consistent_overlap_min {vmin}, expected {weaker[0]}..{weaker[-1]}")
    # INCONSISTENT / UNKNOWN shares of valid-depth pixels (MegaDepth's caveat points here):
    # a copy of pairs.jsonl where one pair has known counts.
    shares = os.path.join(tmp, "shares")
    os.makedirs(shares, exist_ok=True)
    with open(os.path.join(build, "pairs.jsonl")) as f:
        lines = [json.loads(x) for x in f]
    m = lines[0]["metrics"]
    m["01"]["counts"]["INCONSISTENT"] = m["01"]["valid"] // 4
    m["10"]["counts"]["INCONSISTENT"] = 0
    m["01"]["counts"]["UNKNOWN"] = m["10"]["counts"]["UNKNOWN"] = 0
    for p in lines[1:]:
        for d in ("01", "10"):
            p["metrics"][d]["counts"]["INCONSISTENT"] = p["metrics"][d]["counts"]["UNKNOWN"] = 0
    want = (m["01"]["valid"] // 4) / (m["01"]["valid"] + m["10"]["valid"])
    with open(os.path.join(shares, "pairs.jsonl"), "w") as f:
        f.writelines(json.dumps(p) + "\n" for p in lines)
    common.occgt("inspect", "split", shares, "--out", os.path.join(shares, "r"), "--gallery", "0")
    t = open(os.path.join(shares, "r", "report.html"), encoding="utf-8").read()
    for label, hi in (("INCONSISTENT", want), ("UNKNOWN", 0.0)):
        row = re.search(r"<tr><td>%s share of valid-depth pixels \(both directions\)</td>" % label
                        + r"<td class=\"n\">([^<]*)</td>" * 4, t)
        check(row is not None, f"report has no {label} share row")
        if row:
            lo, med, mean, top = (float(v) for v in row.groups())
            check(lo == 0 and abs(top - hi) < 1e-3 and abs(mean - hi / len(lines)) < 1e-3,
                  f"{label} share {row.groups()}, expected max {hi}")
    with open(os.path.join(build, "summary.json")) as f:
        summary = json.load(f)
    for reason, n in summary.get("drops", {}).items():
        check(f"<td>{reason}</td><td class=\"n\">{n}</td>" in text, f"drop {reason} not in report")
    # Byte counts in decimal units beside the raw number; the resolved recipe shown.
    check(re.search(r"<td>bytes_written</td><td class=\"n\">[0-9.]+ [kMG]?B \(%d\)</td>"
                    % summary["bytes_written"], text) is not None,
          "bytes_written not shown in human units")
    check("<h2>Recipe</h2>" in text and html_escape(json.dumps(json.load(open(os.path.join(build, "recipe.json"))),
                                                              indent=2)) in text,
          "report does not show recipe.json")
    # The demo (synthetic, images stored) needs no warning box.
    check('class="warn"' not in text, "demo report shows a warning box")
    chromium_check(html, tmp)
    # Deterministic: a second run writes identical files.
    report2 = os.path.join(tmp, "report2")
    common.occgt("inspect", "split", build, "--out", report2, "--gallery", "3")
    check(open(html, "rb").read() == open(os.path.join(report2, "report.html"), "rb").read(),
          "report.html differs between two runs")

    # --- the gallery's most occluded pairs: the largest mean occlusion ratio first.
    report3 = os.path.join(tmp, "report3")
    common.occgt("inspect", "split", build, "--out", report3, "--gallery", "3",
                 "--gallery-order", "most-occluded")
    text3 = open(os.path.join(report3, "report.html"), encoding="utf-8").read()
    with open(os.path.join(build, "pairs.jsonl")) as f:
        lines = [json.loads(l) for l in f]
    occ = [((p["metrics"]["01"]["occlusion_ratio"] + p["metrics"]["10"]["occlusion_ratio"]) / 2, i, p["key"])
           for i, p in enumerate(lines)]
    want = [k for _, _, k in sorted(occ, key=lambda t: (-t[0], t[1]))[:3]]
    got = re.findall(r"<h3>(\S+)  \(overlap", text3)
    check(got == want, f"most-occluded gallery {got}, expected {want}")
    r = common.occgt("inspect", "split", build, "--gallery-order", "worst", check=False)
    check(r.returncode == 2 and r.stderr.startswith("occgt: error: --gallery-order"), r.stderr)

    # --- a gallery pair whose shard is gone: the page shows the error and the terminal says
    # it (it was on the page only); the report is still written, exit 0.
    cut = os.path.join(tmp, "cut_split")
    shutil.copytree(build, cut, ignore=shutil.ignore_patterns("inspect", "report*"))
    gone = sorted(glob.glob(os.path.join(cut, "*.tar")))
    for t in gone:
        os.remove(t)
    r = common.occgt("inspect", "split", cut, "--out", os.path.join(cut, "r"), "--gallery", "3")
    text5 = open(os.path.join(cut, "r", "report.html"), encoding="utf-8").read()
    check(text5.count("could not be read: ") == 3, "cut split: the page does not show 3 errors")
    check(r.stderr.count("\n") == 1 and r.stderr.startswith(
        "occgt: warning: 3 gallery entries could not be read (first: ") and
        ".tar: cannot open the tar archive" in r.stderr, f"cut split stderr: {r.stderr!r}")

    # --- a split with a caveat and no images: the warning box says both.
    plain = os.path.join(tmp, "plain")
    os.makedirs(plain)
    for name in ("pairs.jsonl", "summary.json"):
        shutil.copyfile(os.path.join(build, name), os.path.join(plain, name))
    rec = json.load(open(os.path.join(build, "recipe.json")))
    rec["dataset"]["format"] = "sevenscenes"
    rec["sample"]["image"] = "none"
    json.dump(rec, open(os.path.join(plain, "recipe.json"), "w"))
    common.occgt("inspect", "split", plain, "--gallery", "0")
    text4 = open(os.path.join(plain, "inspect", "report.html"), encoding="utf-8").read()
    box = re.search(r'<div class="warn" role="alert">(.*?)</div>', text4, re.S)
    check(box is not None, "no warning box for a 7-Scenes split without images")
    if box:
        items = re.findall(r"<li>(.*?)</li>", box.group(1))
        check(len(items) == 2 and "No images are stored" in items[0] and "unregistered" in items[1],
              f"warning items {items}")

    # --- pair from a shard: sizes, label blend, match colours.
    with open(os.path.join(build, "pairs.jsonl")) as f:
        lines = [json.loads(l) for l in f if l.strip()]
    line = lines[0]
    out = os.path.join(tmp, "pair_shard")
    common.occgt("inspect", "pair", "--shard", os.path.join(build, line["shard"]), "--key",
                 line["key"], "--out", out)
    fields = read_sample(os.path.join(build, line["shard"]), line["key"])
    label01 = np.load(io.BytesIO(fields["label01.npy"]))
    types = np.load(io.BytesIO(fields["match_type.npy"]))
    image0 = np.asarray(Image.open(io.BytesIO(fields["image0.png"])).convert("RGB")).astype(float)
    h, w = label01.shape
    matches = png(os.path.join(out, "matches.png"))
    check(matches.shape[1] == 2 * w + PANEL_GAP and matches.shape[0] > h,
          f"matches.png size {matches.shape} for {w}x{h}")
    not_blank(matches, "matches.png")
    has_yellow = bool(np.any(np.all(matches[:h] == VO_RGB, axis=-1)))
    check(has_yellow == bool(np.any(types == 1)), "yellow lines iff vo matches")
    labels = png(os.path.join(out, "labels.png"))
    check(labels.shape[1] == 2 * w + PANEL_GAP and labels.shape[0] > h + 22,
          f"labels.png size {labels.shape}")
    panel = labels[22:22 + h, :w].astype(float)
    colours = np.array(LABEL_RGB, dtype=float)[label01]
    expected = (1 - ALPHA) * image0 + ALPHA * colours
    err = np.abs(panel - expected).max()
    check(err <= 1.0, f"labels.png differs from the documented blend by {err}")
    occ = png(os.path.join(out, "occupancy.png"))
    not_blank(occ, "occupancy.png")
    # The same sample as written before its json took occupancy.json's names (bin edges as
    # "occupancy"."bin_edges_m", "voxel_size_m"): the same occupancy picture.
    old_tar = os.path.join(tmp, "old_keys", os.path.basename(line["shard"]))
    os.makedirs(os.path.dirname(old_tar), exist_ok=True)
    with tarfile.open(os.path.join(build, line["shard"])) as src, \
            tarfile.open(old_tar, "w", format=tarfile.USTAR_FORMAT) as dst:
        rewritten = 0
        for m in src.getmembers():
            data = src.extractfile(m).read()
            if m.name in (line["key"] + ".json", line["key"] + ".json.gz"):
                gz = m.name.endswith(".gz")
                meta = json.loads(gzip.decompress(data) if gz else data)
                check(meta["occupancy"]["bins"]["edges_m"] and "bin_edges_m" not in
                      meta["occupancy"], f"sample json occupancy keys: {list(meta['occupancy'])}")
                data = json.dumps(old_style_sample_json(meta)).encode()
                data = gzip.compress(data) if gz else data
                m.size = len(data)
                rewritten += 1
            dst.addfile(m, io.BytesIO(data))
        check(rewritten == 1, f"old-style shard: {rewritten} json members rewritten")
    out_old = os.path.join(tmp, "pair_shard_old_keys")
    common.occgt("inspect", "pair", "--shard", old_tar, "--key", line["key"], "--out", out_old)
    check(open(os.path.join(out_old, "occupancy.png"), "rb").read() ==
          open(os.path.join(out, "occupancy.png"), "rb").read(),
          "old-style sample json: occupancy.png differs from the current sample's")

    # --- pair computed from the real TartanAir sample.
    root = common.shared("tartanair/hospital_sample")
    out = os.path.join(tmp, "pair_tartanair")
    r = common.occgt("inspect", "pair", "--root", root, "--format", "tartanair", "--scene",
                     "hospital_sample", "--frames", "000000,000010", "--out", out)
    for name in ["matches.png", "labels.png", "occupancy.png"]:
        img = png(os.path.join(out, name))
        not_blank(img, "tartanair " + name)
        check(img.shape[1] >= 2 * 640 + PANEL_GAP, f"tartanair {name}: width {img.shape[1]}")

    # --- an `occgt pair` folder, colour found through meta.json + --root.
    pair_dir = os.path.join(tmp, "occgt_pair")
    common.occgt("pair", "--root", root, "--format", "tartanair", "--scene", "hospital_sample",
                 "--frames", "000000,000020", "--out", pair_dir)
    out = os.path.join(tmp, "pair_dir_pictures")
    common.occgt("inspect", "pair", "--pair-dir", pair_dir, "--root", root, "--out", out)
    label01 = np.load(os.path.join(pair_dir, "label01.npy"))
    colour0 = np.asarray(Image.open(os.path.join(root, "image_left", "000000_left.png"))
                         .convert("RGB")).astype(float)
    check(colour0.shape[:2] == label01.shape, "TartanAir colour is at the working resolution")
    labels = png(os.path.join(out, "labels.png"))
    h, w = label01.shape
    expected = (1 - ALPHA) * colour0 + ALPHA * np.array(LABEL_RGB, dtype=float)[label01]
    err = np.abs(labels[22:22 + h, :w].astype(float) - expected).max()
    check(err <= 1.0, f"pair-dir labels.png differs from the documented blend by {err}")
    check(not os.path.exists(os.path.join(out, "occupancy.png")), "occupancy.png without occupancy")

    # --- `occgt occupancy` outputs: with the `occgt pair` files in one folder, alone, and
    # alone with only the dense volumes. The occupancy picture is the one of the same pair
    # computed from the scene (same defaults: pair scope, 5 cm voxels, 64 bins in [0.1, 10] m).
    computed = os.path.join(tmp, "pair_computed_020")
    common.occgt("inspect", "pair", "--root", root, "--format", "tartanair", "--scene",
                 "hospital_sample", "--frames", "000000,000020", "--out", computed)
    reference = open(os.path.join(computed, "occupancy.png"), "rb").read()
    common.occgt("occupancy", "--root", root, "--format", "tartanair", "--scene",
                 "hospital_sample", "--frames", "000000,000020", "--out", pair_dir)
    out = os.path.join(tmp, "pair_occ_dir_pictures")
    r = common.occgt("inspect", "pair", "--pair-dir", pair_dir, "--root", root, "--out", out)
    check(sorted(os.listdir(out)) == ["labels.png", "matches.png", "occupancy.png"],
          f"pair + occupancy folder: {sorted(os.listdir(out))}")
    check(open(os.path.join(out, "occupancy.png"), "rb").read() == reference,
          "pair + occupancy folder: occupancy.png differs from the computed pair's")
    check(np.array_equal(png(os.path.join(out, "labels.png")), labels),
          "pair + occupancy folder: labels.png differs from the pair folder's")
    occ_dir = os.path.join(tmp, "occgt_occupancy")
    common.occgt("occupancy", "--root", root, "--format", "tartanair", "--scene",
                 "hospital_sample", "--frames", "000000,000020", "--dense", "--out", occ_dir)
    out = os.path.join(tmp, "occ_dir_pictures")
    r = common.occgt("inspect", "pair", "--pair-dir", occ_dir, "--out", out)
    check("occupancy only" in r.stdout, f"occupancy-only folder: {r.stdout!r}")
    check(sorted(os.listdir(out)) == ["occupancy.png"], f"occupancy folder: {os.listdir(out)}")
    check(open(os.path.join(out, "occupancy.png"), "rb").read() == reference,
          "occupancy folder: occupancy.png differs from the computed pair's")
    for name in ["occ0.npy", "known0.npy", "occ1.npy", "known1.npy"]:
        os.remove(os.path.join(occ_dir, name))
    out = os.path.join(tmp, "occ_dense_dir_pictures")
    common.occgt("inspect", "pair", "--pair-dir", occ_dir, "--out", out)
    check(open(os.path.join(out, "occupancy.png"), "rb").read() == reference,
          "dense-only occupancy folder: occupancy.png differs from the computed pair's")
    # A folder written before the dense volumes took the shard's names (occupancy0/1.npy) and
    # occupancy.json its voxel_m: read alike.
    meta = json.load(open(os.path.join(occ_dir, "occupancy.json")))
    check(meta["files"][-2:] == ["occ0_dense.npy", "occ1_dense.npy"] and
          "voxel_m" in meta["fusion"], f"occupancy.json names: {meta['files']}, {meta['fusion']}")
    for c in "01":
        os.rename(os.path.join(occ_dir, f"occ{c}_dense.npy"),
                  os.path.join(occ_dir, f"occupancy{c}.npy"))
    meta["fusion"]["voxel_size_m"] = meta["fusion"].pop("voxel_m")
    meta["files"][-2:] = ["occupancy0.npy", "occupancy1.npy"]
    json.dump(meta, open(os.path.join(occ_dir, "occupancy.json"), "w"))
    out = os.path.join(tmp, "occ_old_names_dir_pictures")
    common.occgt("inspect", "pair", "--pair-dir", occ_dir, "--out", out)
    check(open(os.path.join(out, "occupancy.png"), "rb").read() == reference,
          "old-style dense occupancy folder: occupancy.png differs from the computed pair's")
    os.remove(os.path.join(occ_dir, "occupancy.json"))
    r = common.occgt("inspect", "pair", "--pair-dir", occ_dir, "--out", out, check=False)
    check(r.returncode == 1 and "edges_m" in r.stderr and len(r.stderr.strip().splitlines()) == 1,
          f"occupancy folder without occupancy.json: exit {r.returncode}, {r.stderr!r}")

    # --- a computed pair takes a recipe's settings as `occgt pair --recipe` does: the recipe's
    # labels (here the occ2net preset and a 6 m depth limit) give the same label panel as the
    # `occgt pair` folder of that recipe, and another panel than the defaults.
    recipe = os.path.join(tmp, "inspect_recipe.yaml")
    with open(recipe, "w") as f:
        f.write("name: inspect-recipe\nsplit: inspect-recipe\nresolution: [320, 240]\n"
                f"dataset: {{format: tartanair, root: {root}, max_depth_m: 6}}\n"
                "labels: {preset: occ2net}\noccupancy: {enabled: false}\n")
    frames = ["--scene", "hospital_sample", "--frames", "000000,000020"]
    recipe_pair = os.path.join(tmp, "recipe_pair")
    common.occgt("pair", "--recipe", recipe, *frames, "--out", recipe_pair)
    from_dir = os.path.join(tmp, "recipe_pair_pictures")
    common.occgt("inspect", "pair", "--pair-dir", recipe_pair, "--root", root, "--out", from_dir)
    computed = os.path.join(tmp, "recipe_computed")
    r = common.occgt("inspect", "pair", "--recipe", recipe, *frames, "--out", computed)
    check(sorted(os.listdir(computed)) == ["labels.png", "matches.png"],
          f"recipe without occupancy: {sorted(os.listdir(computed))}")
    recipe_labels = png(os.path.join(computed, "labels.png"))
    check(recipe_labels.shape[1] < 2 * 640, f"the recipe's 320x240: {recipe_labels.shape}")
    check(np.array_equal(recipe_labels, png(os.path.join(from_dir, "labels.png"))),
          "inspect pair --recipe: labels.png differs from `occgt pair --recipe`'s folder")
    defaults = os.path.join(tmp, "recipe_defaults")
    common.occgt("inspect", "pair", "--root", root, "--format", "tartanair", "--resolution",
                 "320x240", "--no-occupancy", *frames, "--out", defaults)
    check(not np.array_equal(recipe_labels, png(os.path.join(defaults, "labels.png"))),
          "inspect pair --recipe: the recipe's labels changed nothing")
    # A folder holding an earlier pair's occupancy.png: a pair without occupancy removes it
    # (it stayed beside the new labels.png, as if it were this pair's).
    stale = os.path.join(tmp, "stale_pictures")
    common.occgt("inspect", "pair", "--root", root, "--format", "tartanair", "--resolution",
                 "320x240", *frames, "--out", stale)
    check(os.path.exists(os.path.join(stale, "occupancy.png")), "no occupancy.png to begin with")
    common.occgt("inspect", "pair", "--root", root, "--format", "tartanair", "--resolution",
                 "320x240", "--no-occupancy", *frames, "--out", stale)
    check(sorted(os.listdir(stale)) == ["labels.png", "matches.png"],
          f"an earlier pair's picture left: {sorted(os.listdir(stale))}")
    r = common.occgt("inspect", "pair", "--recipe", recipe, "--out", computed, check=False)
    check(r.returncode == 2 and "--scene/--frames" in r.stderr,
          f"--recipe without frames: exit {r.returncode}, {r.stderr!r}")

    # --- a sample of a split built with sample.labels: false (its matches without the label
    # maps): one line saying so, not "missing field label01.npy" as for a damaged sample.
    first_tar = sorted(glob.glob(os.path.join(build, "*.tar")))[0]
    nolabels = os.path.join(tmp, "nolabels.tar")
    with tarfile.open(first_tar) as src, tarfile.open(nolabels, "w") as dst:
        first_key = None
        for m in src.getmembers():
            key = m.name.split(".", 1)[0]
            first_key = first_key or key
            if key == first_key and ".label0" not in m.name and ".label1" not in m.name:
                dst.addfile(m, src.extractfile(m))
    r = common.occgt("inspect", "pair", "--shard", nolabels, "--key", first_key, "--out",
                     os.path.join(tmp, "nolabels_pictures"), check=False)
    check(r.returncode == 1 and r.stderr.count("\n") == 1 and
          "holds no label maps (label01.npy, label10.npy): a split built with sample.labels: "
          "false" in r.stderr, f"labels: false sample: exit {r.returncode}, {r.stderr!r}")

    # --- one report per folder at a time: while another inspect split holds the folder's
    # lock (byte 0 of .inspect.lock, as occgt's FileLock), a second one is refused and
    # touches nothing (it took the first one's files for an earlier run's).
    held = os.path.join(report, ".inspect.lock")
    check(os.path.exists(held), "inspect split holds no lock file in its report folder")
    before = {n: os.path.getmtime(os.path.join(report, n)) for n in os.listdir(report)}
    fd = os.open(held, os.O_RDWR)
    try:
        fcntl.lockf(fd, fcntl.LOCK_EX | fcntl.LOCK_NB, 1, 0)
        r = common.occgt("inspect", "split", build, "--out", report, check=False)
    finally:
        os.close(fd)
    check(r.returncode == 1 and r.stderr.strip() ==
          f"occgt: error: {report}: another occgt inspect split is writing this report folder "
          f"now (it holds {held}); wait for it to end or use another --out",
          f"a second inspect split into a held folder: exit {r.returncode}, {r.stderr!r}")
    check({n: os.path.getmtime(os.path.join(report, n)) for n in os.listdir(report)} == before,
          "the refused run changed the report folder")
    # A run that fails creates no folder (the lock file is not left behind).
    r = common.occgt("inspect", "split", os.path.join(tmp, "no_such_split"), "--out",
                     os.path.join(tmp, "no_report"), check=False)
    check(r.returncode == 1 and not os.path.exists(os.path.join(tmp, "no_report")),
          f"a failed inspect split left its report folder: exit {r.returncode}")

    # --- a damaged sample (its first match moved 3 cells to the right, out of the cell that
    # matches.npy names; the shard's size and MD5 updated) is named by the rules of occgt
    # validate, not drawn with the match pointing elsewhere (10012e9 drew it).
    damaged = os.path.join(tmp, "damaged_split")
    shutil.rmtree(damaged, ignore_errors=True)
    shutil.copytree(build, damaged)

    def move_match(plain: bytes) -> bytes:
        a = np.load(io.BytesIO(plain))
        a[0, 0] += 24
        out = io.BytesIO()
        np.save(out, a)
        return out.getvalue()

    damaged_tar = sorted(glob.glob(os.path.join(damaged, "*.tar")))[0]
    damaged_key = common.edit_first_sample_member(damaged_tar, "match_xy.npy", move_match)
    r = common.occgt("inspect", "pair", "--shard", damaged_tar, "--key", damaged_key, "--out",
                     os.path.join(tmp, "damaged_pictures"), check=False)
    check(r.returncode == 1 and len(r.stderr.strip().splitlines()) == 1 and
          r.stderr.startswith(f"occgt: error: {damaged_tar}:{damaged_key}.match_xy.npy: row 0 ("),
          f"damaged sample: exit {r.returncode}, {r.stderr!r}")
    check(not os.path.exists(os.path.join(tmp, "damaged_pictures", "matches.png")),
          "a damaged sample drawn")

    # --- split written by the test: no pairs at all, and a malformed line.
    empty = os.path.join(tmp, "empty_split")
    os.makedirs(empty)
    open(os.path.join(empty, "pairs.jsonl"), "w").close()
    with open(os.path.join(empty, "summary.json"), "w") as f:
        json.dump({"split": "empty", "drops": {"filter.overlap": 7}}, f)
    common.occgt("inspect", "split", empty)
    for name in ["overlap_hist.png", "occlusion_cumulative.png", "pairs_per_scene.png"]:
        not_blank(png(os.path.join(empty, "inspect", name)), "empty split " + name)
    # report.json: no pair, no statistic (null, not 0), and it follows its schema.
    with open(os.path.join(empty, "inspect", "report.json")) as f:
        report = json.load(f)
    with open(os.path.join(common.SOURCE, "schemas", "report.schema.json")) as f:
        jsonschema.validate(report, json.load(f), cls=jsonschema.Draft202012Validator)
    check(report["pairs"]["count"] == 0 and
          set(report["pairs"]["overlap"].values()) == {None},
          f"empty split: {report['pairs']}")
    with open(os.path.join(empty, "pairs.jsonl"), "w") as f:
        f.write(json.dumps({"scene": "a", "frame0": "1", "frame1": "2",
                            "metrics": {"01": {"overlap": 0.5}, "10": {}}}) + "\n")
    r = common.occgt("inspect", "split", empty, check=False)
    check(r.returncode == 1, f"malformed pairs.jsonl: exit {r.returncode}")
    check("pairs.jsonl:1" in r.stderr and len(r.stderr.strip().splitlines()) == 1,
          f"malformed pairs.jsonl: stderr {r.stderr!r}")
    # Edited lines of a real split: a key that is not a string (was the JSON library's own
    # message, naming no file), an overlap outside [0, 1] (was reported as its maximum) and a
    # repeated line (counted twice): one line naming the file and line, exit 1.
    with open(os.path.join(build, "pairs.jsonl")) as f:
        real = [json.loads(x) for x in f]
    edits = [
        (lambda ls: ls[1].update(key=5), r"pairs\.jsonl:2: key: expected a string, got 5"),
        (lambda ls: ls[2]["metrics"]["01"].update(overlap=7.5),
         r"pairs\.jsonl:3: metrics\.01\.overlap: expected a number in \[0, 1\], got 7\.5"),
        # The field named by its path, and what it held instead.
        (lambda ls: ls[2]["metrics"]["01"].update(overlap="0.5"),
         r"pairs\.jsonl:3: metrics\.01\.overlap: expected a number, got a string$"),
        (lambda ls: ls[2]["metrics"]["10"]["counts"].pop("UNKNOWN"),
         r"pairs\.jsonl:3: metrics\.10\.counts\.UNKNOWN: missing: expected a number$"),
        (lambda ls: ls.extend(ls[:1]),
         r"pairs\.jsonl:%d: key \S+ repeats \S+pairs\.jsonl:1 " % (len(real) + 1)),
    ]
    for edit, pattern in edits:
        edited = os.path.join(tmp, "edited")
        shutil.rmtree(edited, ignore_errors=True)
        os.makedirs(edited)
        for name in ("summary.json", "index.json", "recipe.json"):
            shutil.copyfile(os.path.join(build, name), os.path.join(edited, name))
        lines_e = json.loads(json.dumps(real))
        edit(lines_e)
        with open(os.path.join(edited, "pairs.jsonl"), "w") as f:
            f.write("".join(json.dumps(x) + "\n" for x in lines_e))
        r = common.occgt("inspect", "split", edited, check=False)
        check(r.returncode == 1 and len(r.stderr.strip().splitlines()) == 1 and
              re.search(pattern, r.stderr.strip()) is not None,
              f"edited pairs.jsonl /{pattern}/: exit {r.returncode}, stderr {r.stderr!r}")
    r = common.occgt("inspect", "pair", "--shard", os.path.join(build, line["shard"]), "--key",
                     "no/such_key", "--out", os.path.join(tmp, "x"), check=False)
    check(r.returncode == 1 and "no/such_key" in r.stderr, f"missing key: {r.stderr!r}")
    check(not os.path.exists(os.path.join(tmp, "x", "matches.png")), "wrote output on error")

    print(f"{0 if failures else 1} passed, {len(failures)} failed")
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
