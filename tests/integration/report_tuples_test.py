"""The tuples section of `occgt inspect split` (libgt/report/tuples_report.h, docs/INSPECT.md).

A synthetic recipe built with `occgt build`, `occgt covis` and `occgt tuples --shards` into one
folder; the report's numbers (report.json, and the rounded ones of report.html) equal those
computed here from tuples.jsonl and from the N-view shards' own bits: tuple sizes, the
off-diagonal covisibility values (statistics and histogram), the per-tuple occlusion of the
ground truth (OCCLUDED / (VISIBLE + OCCLUDED) bits of the ordered pairs, from visible_in /
occluded_in) and of the graph estimate (tuples.jsonl "occlusion"); the gallery is the seeded
choice re-computed here, with one thumbnail per view; report.json validates against
schemas/report.schema.json. Then a folder of tuples only (no pairs.jsonl), one without shards,
the same report twice (byte-identical), and bad inputs.
"""
import gzip
import io
import json
import math
import os
import re
import shutil
import sys
import tarfile

import jsonschema
import numpy as np
from PIL import Image

sys.path.insert(0, os.path.dirname(__file__))
import common  # noqa: E402

RECIPE = """name: report-tuples-test
split: rt
seed: 3
resolution: [96, 72]
dataset:
  format: synthetic
  synthetic: {scenes: 2, frames: 10, width: 96, height: 72, seed: 4}
  frame_stride: 1
  min_valid_depth_fraction: 0.3
labels: {preset: default}
selection:
  max_frame_gap: 4
  pruning: {max_distance_m: 4.0, max_view_angle_deg: 120, frustum: true}
  score_stride: 4
  overlap: [0.0, 1.0]
  visible_overlap: [0.0, 1.0]
  occlusion: [0.0, 1.0]
  quota_per_scene: 6
  views: [3, 5]
  tuples: {edge_threshold: 0.2, pair_covisibility: [0.0, 0.97], restarts: 4, quota_per_scene: 5,
           balance_occlusion: 3}
occupancy: {enabled: false}
shards: {samples_per_shard: 4}
sample: {image: png, depth: true, labels: true, occupancy: false}
"""

BINS = 10
SEED = 7
GALLERY = 3
M64 = (1 << 64) - 1

failures = []


def check(cond, msg):
    if not cond:
        failures.append(msg)
        print("FAIL:", msg)


def splitmix64(x):
    x = (x + 0x9E3779B97F4A7C15) & M64
    x = ((x ^ (x >> 30)) * 0xBF58476D1CE4E5B9) & M64
    x = ((x ^ (x >> 27)) * 0x94D049BB133111EB) & M64
    return x ^ (x >> 31)


def fnv1a64(s):
    h = 0xCBF29CE484222325
    for c in s.encode():
        h = ((h ^ c) * 0x100000001B3) & M64
    return h


def describe(values):
    """count, min, median, mean, max and the histogram of the documented rule."""
    hist = [0] * BINS
    for v in values:
        hist[min(max(math.floor(v * BINS), 0), BINS - 1)] += 1
    if not values:
        return {"count": 0, "min": None, "median": None, "mean": None, "max": None, "histogram": hist}
    s = sorted(values)
    n = len(s)
    return {"count": n, "min": s[0], "max": s[-1], "mean": sum(values) / n,
            "median": s[n // 2] if n % 2 else 0.5 * (s[n // 2 - 1] + s[n // 2]), "histogram": hist}


def same_distribution(got, want, name):
    check(got["count"] == want["count"], f"{name}: count {got['count']} != {want['count']}")
    check(got["histogram"] == want["histogram"], f"{name}: histogram {got['histogram']} != {want['histogram']}")
    for k in ("min", "median", "mean", "max"):
        if want[k] is None:
            check(got[k] is None, f"{name}.{k}: {got[k]} != null")
        else:
            check(got[k] is not None and abs(got[k] - want[k]) <= 1e-12,
                  f"{name}.{k}: {got[k]} != {want[k]}")


def shard_occlusion(views_dir):
    """tuple_index -> OCCLUDED / (VISIBLE + OCCLUDED) over the ordered pairs i != j, counted
    here from each sample's visible_in / occluded_in bits."""
    out = {}
    for tar_name in sorted(f for f in os.listdir(views_dir) if f.endswith(".tar")):
        samples = {}
        with tarfile.open(os.path.join(views_dir, tar_name)) as tar:
            for m in tar.getmembers():
                key, field = m.name.split(".", 1)
                data = tar.extractfile(m).read()
                if field.endswith(".gz"):
                    field, data = field[:-3], gzip.decompress(data)
                samples.setdefault(key, {})[field] = data
        for fields in samples.values():
            meta = json.loads(fields["json"])
            vis = np.load(io.BytesIO(fields["visible_in.npy"]))
            occ = np.load(io.BytesIO(fields["occluded_in.npy"]))
            n = vis.shape[0]
            v = o = 0
            for i in range(n):
                for j in range(n):
                    if i != j:
                        v += int(((vis[i] >> j) & 1).sum())
                        o += int(((occ[i] >> j) & 1).sum())
            out[meta["tuple_index"]] = o / (v + o) if v + o else 0.0
    return out


def expected(lines, occlusion_truth):
    sizes = {}
    for t in lines:
        sizes[str(len(t["frame_ids"]))] = sizes.get(str(len(t["frame_ids"])), 0) + 1
    cov = [t["covisibility"][a][b] for t in lines
           for a in range(len(t["frame_ids"])) for b in range(len(t["frame_ids"])) if a != b]
    occ = {}
    if occlusion_truth is not None:
        occ["ground_truth"] = describe([occlusion_truth[k] for k in range(len(lines))])
    if any("occlusion" in t for t in lines):
        occ["graph_estimate"] = describe([t["occlusion"] for t in lines if "occlusion" in t])
    return sizes, describe(cov), occ


def gallery_choice(lines):
    seed_hash = splitmix64(SEED)
    keyed = sorted((splitmix64(seed_hash ^ fnv1a64(t["scene"] + ":" + ",".join(t["frame_ids"]))), k)
                   for k, t in enumerate(lines))
    return sorted(k for _, k in keyed[:GALLERY])


def read_report(out):
    with open(os.path.join(out, "report.json")) as f:
        doc = json.load(f)
    with open(os.path.join(common.SOURCE, "schemas", "report.schema.json")) as f:
        schema = json.load(f)
    try:
        jsonschema.validate(doc, schema)
    except jsonschema.ValidationError as e:
        check(False, f"{out}/report.json does not validate: {e.message}")
    with open(os.path.join(out, "report.html"), encoding="utf-8") as f:
        html = f.read()
    return doc, html


def html_row(html, label):
    m = re.search(r"<tr><td>%s</td><td class=\"n\">(\d+)</td>" % re.escape(label) +
                  r"<td class=\"n\">([^<]*)</td>" * 4, html)
    check(m is not None, f"report.html has no row '{label}'")
    return [float(x) for x in m.groups()] if m else None


def check_tuples(doc, html, lines, truth, label):
    t = doc["tuples"]
    check(t is not None, f"{label}: report.json has no tuples")
    if t is None:
        return
    sizes, cov, occ = expected(lines, truth)
    check(t["count"] == len(lines), f"{label}: count {t['count']} != {len(lines)}")
    check(t["scenes"] == len({x["scene"] for x in lines}), f"{label}: scenes {t['scenes']}")
    check(t["sizes"] == sizes, f"{label}: sizes {t['sizes']} != {sizes}")
    check(t["has_shards"] == (truth is not None), f"{label}: has_shards {t['has_shards']}")
    same_distribution(t["covisibility"], cov, f"{label}: covisibility")
    check(sorted(t["occlusion"]) == sorted(occ), f"{label}: occlusion sources {sorted(t['occlusion'])} != {sorted(occ)}")
    for source in occ:
        if source in t["occlusion"]:
            same_distribution(t["occlusion"][source], occ[source], f"{label}: occlusion.{source}")
    # The HTML shows the same numbers (4 significant digits) and sizes.
    row = html_row(html, "covisibility (ordered pairs of views)")
    if row:
        check(row[0] == cov["count"], f"{label}: html covisibility count {row[0]}")
        for got, key in zip(row[1:], ("min", "median", "mean", "max")):
            check(abs(got - cov[key]) <= 5e-4 * max(1.0, abs(cov[key])), f"{label}: html covisibility {key} {got} vs {cov[key]}")
    for source, name in (("ground_truth", "occlusion (N-view ground truth)"),
                         ("graph_estimate", "occlusion (graph estimate)")):
        if source in occ:
            row = html_row(html, name)
            if row:
                check(abs(row[3] - occ[source]["mean"]) <= 5e-4, f"{label}: html {name} mean {row[3]}")
    for n, count in sizes.items():
        check(f"<tr><td>{n}</td><td class=\"n\">{count}</td></tr>" in html, f"{label}: html has no size row {n}")
    # Gallery: the seeded choice, with one thumbnail per view when the shards exist.
    want = gallery_choice(lines)
    got = [g["index"] for g in t["gallery"]]
    check(got == want, f"{label}: gallery {got} != {want}")
    for g in t["gallery"]:
        line = lines[g["index"]]
        check(g["frame_ids"] == line["frame_ids"] and g["scene"] == line["scene"], f"{label}: gallery entry {g}")
        for v, fid in enumerate(line["frame_ids"]):
            present = f"<figcaption>view {v}: {fid}</figcaption>" in html
            check(present == (truth is not None), f"{label}: thumbnail of view {v} of tuple {g['index']} present={present}")


def main():
    tmp = common.scratch("report_tuples")
    recipe = os.path.join(tmp, "recipe.yaml")
    with open(recipe, "w") as f:
        f.write(RECIPE)
    out = os.path.join(tmp, "out")
    common.occgt("build", recipe, "--out", out)
    common.occgt("covis", recipe, "--out", out)
    common.occgt("tuples", recipe, "--out", out, "--shards")
    with open(os.path.join(out, "tuples.jsonl")) as f:
        lines = [json.loads(x) for x in f]
    check(len(lines) >= 6, f"only {len(lines)} tuples")
    check(len({len(t['frame_ids']) for t in lines}) >= 2, "every tuple has the same size")
    truth = shard_occlusion(os.path.join(out, "views"))
    check(sorted(truth) == list(range(len(lines))), "shards do not hold one sample per tuple")
    check(any(v > 0 for v in truth.values()), "no tuple has occluded pixels")
    # validate: each views/pairs.jsonl line's values are its sample json's (a frame id or
    # the occlusion ratio edited in the line was passed before).
    views = os.path.join(out, "views")
    common.occgt("validate", views)
    edited = os.path.join(tmp, "views_edited")
    shutil.rmtree(edited, ignore_errors=True)
    shutil.copytree(views, edited)
    with open(os.path.join(edited, "pairs.jsonl")) as f:
        view_lines = [json.loads(x) for x in f]
    view_lines[1]["frame_ids"][0] = "x" + view_lines[1]["frame_ids"][0]
    view_lines[2]["occlusion_ratio_visible"] = 0.5
    with open(os.path.join(edited, "pairs.jsonl"), "w") as f:
        f.write("".join(json.dumps(x) + "\n" for x in view_lines))
    r = common.occgt("validate", edited, check=False)
    got = [x.split(": ", 1)[1] for x in r.stdout.splitlines()]
    check(r.returncode == 1 and got == [
        f'field "frame_ids" differs from the sample\'s json ({view_lines[1]["shard"]}, '
        f'{view_lines[1]["key"]})',
        f'field "occlusion_ratio_visible" differs from the sample\'s json '
        f'({view_lines[2]["shard"]}, {view_lines[2]["key"]})'], f"validate of edited lines: {r.stdout}")

    # inspect pair draws pair samples: an N-view sample is refused by name (it was "missing
    # field label01.npy", as if a pair sample were damaged).
    first = view_lines[0]
    r = common.occgt("inspect", "pair", "--shard", os.path.join(views, first["shard"]), "--key",
                     first["key"], "--out", os.path.join(tmp, "views_pictures"), check=False)
    check(r.returncode == 1 and r.stderr.strip().endswith(
        f'{first["key"]}: an N-view sample of occgt tuples --shards; inspect pair draws the pair '
        f'samples of occgt build (occgt.torch.TupleShardDataset reads N-view samples)'),
        f"inspect pair of an N-view sample: exit {r.returncode}, {r.stderr!r}")

    # --- a folder with pairs and tuples (and shards).
    report = os.path.join(tmp, "report")
    common.occgt("inspect", "split", out, "--out", report, "--bins", BINS, "--seed", SEED,
                 "--gallery", 2, "--gallery-tuples", GALLERY)
    doc, html = read_report(report)
    with open(os.path.join(out, "pairs.jsonl")) as f:
        n_pairs = sum(1 for _ in f)
    check(doc["pairs"] is not None and doc["pairs"]["count"] == n_pairs, f"pairs {doc['pairs']}")
    check_tuples(doc, html, lines, truth, "build+tuples")
    for name in ("tuple_sizes.png", "tuple_covisibility_hist.png", "tuple_occlusion_hist.png"):
        img = np.asarray(Image.open(os.path.join(report, name)).convert("RGB"))
        check(img.shape == (480, 800, 3), f"{name}: size {img.shape}")
        check(len(np.unique(img.reshape(-1, 3), axis=0)) >= 8, f"{name}: blank")
    # Thumbnails: one JPEG per view of each gallery tuple, beside the pairs' gallery images.
    views = sum(len(lines[g["index"]]["frame_ids"]) for g in doc["tuples"]["gallery"])
    check(len(re.findall(r'<figure><img alt="[^"]*: view \d+: ', html)) == views,
          f"expected {views} thumbnails")
    # Deterministic.
    report2 = os.path.join(tmp, "report2")
    common.occgt("inspect", "split", out, "--out", report2, "--bins", BINS, "--seed", SEED,
                 "--gallery", 2, "--gallery-tuples", GALLERY)
    for name in ("report.json", "report.html"):
        check(common_bytes(os.path.join(report, name)) == common_bytes(os.path.join(report2, name)),
              f"{name} differs between two runs")

    # --- tuples only (no pairs.jsonl): the tuples section alone.
    only = os.path.join(tmp, "only")
    os.makedirs(only)
    shutil.copy(os.path.join(out, "tuples.jsonl"), only)
    shutil.copytree(os.path.join(out, "views"), os.path.join(only, "views"))
    r = common.occgt("inspect", "split", only, "--out", os.path.join(only, "r"), "--bins", BINS,
                     "--seed", SEED, "--gallery-tuples", GALLERY)
    doc, html = read_report(os.path.join(only, "r"))
    check(doc["pairs"] is None, "tuples-only report has pairs")
    check("No pairs.jsonl in this folder" in html and "overlap_hist.png" not in html,
          "tuples-only report shows pair plots")
    check('class="warn"' not in html, "tuples-only report shows a warning")
    check(f"no pairs.jsonl &middot; {len(lines)} N-view tuples</p>" in html,
          "tuples-only report's heading does not say what the folder holds")
    check_tuples(doc, html, lines, truth, "tuples only")

    # --- N-view shards written before occgt 0.2 name the ground truth occluded_fraction:
    # read as the same number.
    old = os.path.join(tmp, "old_names")
    shutil.copytree(only, old)
    shutil.rmtree(os.path.join(old, "r"))
    with open(os.path.join(old, "views", "pairs.jsonl")) as f:
        rows = [json.loads(x) for x in f]
    for row in rows:
        row["occluded_fraction"] = row.pop("occlusion_ratio_visible")
    with open(os.path.join(old, "views", "pairs.jsonl"), "w") as f:
        f.writelines(json.dumps(x) + "\n" for x in rows)
    common.occgt("inspect", "split", old, "--out", os.path.join(old, "r"), "--bins", BINS,
                 "--seed", SEED, "--gallery-tuples", GALLERY)
    doc, html = read_report(os.path.join(old, "r"))
    check_tuples(doc, html, lines, truth, "pre-0.2 names")

    # --- the N-view shards' tar files gone: every gallery tuple's error is on the page and
    # the terminal says how many (the report is still written).
    cut = os.path.join(tmp, "cut_views")
    shutil.copytree(old, cut)
    shutil.rmtree(os.path.join(cut, "r"))
    for name in os.listdir(os.path.join(cut, "views")):
        if name.endswith(".tar"):
            os.remove(os.path.join(cut, "views", name))
    r = common.occgt("inspect", "split", cut, "--out", os.path.join(cut, "r"), "--bins", BINS,
                     "--seed", SEED, "--gallery-tuples", GALLERY)
    check(r.stderr.count("\n") == 1 and r.stderr.startswith(
        f"occgt: warning: {GALLERY} gallery entries could not be read (first: tuple "),
        f"cut views stderr: {r.stderr!r}")

    # --- no shards: occlusion from tuples.jsonl only, no thumbnails (said why).
    bare = os.path.join(tmp, "bare")
    os.makedirs(bare)
    shutil.copy(os.path.join(out, "tuples.jsonl"), bare)
    common.occgt("inspect", "split", bare, "--out", os.path.join(bare, "r"), "--bins", BINS,
                 "--seed", SEED, "--gallery-tuples", GALLERY)
    doc, html = read_report(os.path.join(bare, "r"))
    check_tuples(doc, html, lines, None, "no shards")
    check("occgt tuples --shards` writes the views shown here" in html, "no-shards gallery says nothing")

    # --- a build without tuples: "tuples": null.
    plain = os.path.join(tmp, "plain")
    os.makedirs(plain)
    shutil.copy(os.path.join(out, "pairs.jsonl"), plain)
    common.occgt("inspect", "split", plain, "--out", os.path.join(plain, "r"), "--gallery", 0)
    doc, html = read_report(os.path.join(plain, "r"))
    check(doc["tuples"] is None and doc["pairs"]["count"] == n_pairs, "plain build report")
    check("<h2>Tuples</h2>" not in html, "plain build report has a tuples section")

    # --- bad inputs: one line naming the file; usage errors exit 2.
    with open(os.path.join(only, "views", "pairs.jsonl")) as f:
        rows = [json.loads(x) for x in f]
    rows[1]["frame_ids"] = list(reversed(rows[1]["frame_ids"]))
    with open(os.path.join(only, "views", "pairs.jsonl"), "w") as f:
        f.writelines(json.dumps(x) + "\n" for x in rows)
    r = common.occgt("inspect", "split", only, "--out", os.path.join(only, "r2"), check=False)
    check(r.returncode == 1 and r.stderr.count("\n") == 1 and "views/pairs.jsonl:2" in r.stderr
          and "names other frames" in r.stderr, f"mismatched views line: {r.returncode} {r.stderr!r}")
    with open(os.path.join(bare, "tuples.jsonl"), "a") as f:
        f.write('{"scene": "x", "frame_ids": ["a", "b"], "covisibility": [[1, 0]]}\n')
    r = common.occgt("inspect", "split", bare, "--out", os.path.join(bare, "r2"), check=False)
    check(r.returncode == 1 and r.stderr.count("\n") == 1 and
          f"tuples.jsonl:{len(lines) + 1}" in r.stderr and "covisibility" in r.stderr,
          f"malformed tuples line: {r.returncode} {r.stderr!r}")
    # Lines that break schemas/tuples_line.schema.json: one line naming the line and field
    # (a score out of [0, 1] used to reach report.json, which then broke report.schema.json).
    def bad_line(edit, message):
        t = json.loads(json.dumps(lines[0]))
        edit(t)
        with open(os.path.join(bare, "tuples.jsonl"), "w") as f:
            f.writelines(json.dumps(x) + "\n" for x in lines + [t])
        r = common.occgt("inspect", "split", bare, "--out", os.path.join(bare, "r3"), check=False)
        check(r.returncode == 1 and r.stderr.count("\n") == 1 and
              f"tuples.jsonl:{len(lines) + 1}: " in r.stderr and message in r.stderr,
              f"bad tuples line ({message}): {r.returncode} {r.stderr!r}")

    def many_views(t):
        t["frame_ids"] = [f"{k:06d}" for k in range(33)]
        t["covisibility"] = [[0.5] * 33 for _ in range(33)]

    bad_line(lambda t: t["covisibility"][0].__setitem__(1, 2.0),
             '"covisibility"[0][1] is 2.0, expected a number in [0, 1]')
    bad_line(lambda t: t["covisibility"][0].__setitem__(1, -1.0),
             '"covisibility"[0][1] is -1.0, expected a number in [0, 1]')
    bad_line(many_views, '"frame_ids": an array of 2 to 32 frame ids, got 33')
    bad_line(lambda t: t["frame_ids"].__setitem__(1, t["frame_ids"][0]),
             f'"frame_ids": \'{lines[0]["frame_ids"][0]}\' repeats, expected distinct frame ids')
    bad_line(lambda t: t.update(extra=1), 'unexpected key "extra"')
    bad_line(lambda t: t.update(scene=""), 'expected a non-empty string "scene"')
    r = common.occgt("inspect", "split", out, "--gallery-tuples", 99, check=False)
    check(r.returncode == 2 and r.stderr.startswith("occgt: error: --gallery-tuples"), r.stderr)
    empty = os.path.join(tmp, "empty")
    os.makedirs(empty)
    r = common.occgt("inspect", "split", empty, check=False)
    check(r.returncode == 1 and "pairs.jsonl" in r.stderr and "tuples.jsonl" in r.stderr, r.stderr)

    if failures:
        sys.exit(f"{len(failures)} failure(s)")
    print("report_tuples: OK")


def common_bytes(path):
    with open(path, "rb") as f:
        return f.read()


if __name__ == "__main__":
    main()
