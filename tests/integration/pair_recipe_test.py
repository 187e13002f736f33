"""`occgt pair --recipe` and `occgt occupancy --recipe` reproduce a built shard (docs/CLI.md).

Builds three recipes (the shipped TartanAir sample: far_m 20, voxel 0.1 and a dataset
max_depth_m; the shipped synthetic demo: far_m 8; a synthetic recipe written here with
non-default labels, patches and a window scope, both volume encodings), then runs the two
single-pair tools with --recipe on pairs of each build and compares the .npy bytes with the
shard's members. Then: flags override the recipe, and without a recipe --far-m is also the
ray range (as a recipe's far_m).
"""
import gzip
import json
import os
import re
import shlex
import subprocess
import sys
import tarfile

sys.path.insert(0, os.path.dirname(__file__))
import common  # noqa: E402

PAIR_MEMBERS = ["label01.npy", "label10.npy", "matches.npy", "match_type.npy", "match_xy.npy",
                "cells0.npy", "cells1.npy"]
OCC_MEMBERS = {"occ0.npy": "occ0.npy", "known0.npy": "known0.npy", "occ1.npy": "occ1.npy",
               "known1.npy": "known1.npy", "occ0_dense.npy": "occ0_dense.npy",
               "occ1_dense.npy": "occ1_dense.npy"}

SYNTH_RECIPE = """name: pair-recipe
split: pair-recipe
resolution: [192, 144]
dataset:
  format: generic
  root: {root}
  min_valid_depth_fraction: 0.3
  max_depth_m: 9.0
labels:
  preset: occ2net
  overrides: {{abs_tol_m: 0.07}}
patches: {{stride: 16, anchor: corner, mutual: false}}
selection:
  max_frame_gap: 4
  score_stride: 4
  overlap: [0.2, 1.0]
  quota_per_scene: 3
occupancy:
  voxel_m: 0.08
  bins: 32
  near_m: 0.2
  far_m: 6.0
  spacing: log
  traversal: center
  scope: window
  window: 1
  encoding: both
sample: {{image: none, depth: false, labels: true, occupancy: true}}
shards: {{samples_per_shard: 4}}
"""


def fail(msg):
    sys.exit(f"FAIL: {msg}")


def shard_members(tar_path, key):
    out = {}
    with tarfile.open(tar_path) as tf:
        for m in tf.getmembers():
            if m.name.startswith(key + "."):
                field, data = m.name[len(key) + 1:], tf.extractfile(m).read()
                if field.endswith(".gz"):  # sample.compression: deflate (the default)
                    field, data = field[:-3], gzip.decompress(data)
                out[field] = data
    return out


def read(path):
    with open(path, "rb") as f:
        return f.read()


def check_pairs(name, recipe, build, extra=()):
    """Reproduces the first and the last sample of the build with the single-pair tools."""
    with open(os.path.join(build, "pairs.jsonl")) as f:
        lines = [json.loads(l) for l in f if l.strip()]
    if not lines:
        fail(f"{name}: the build selected no pairs")
    for line in [lines[0], lines[-1]] if len(lines) > 1 else lines:
        members = shard_members(os.path.join(build, line["shard"]), line["key"])
        frames = f"{line['frame0']['id']},{line['frame1']['id']}"
        tag = f"{name} {line['key']}"
        pair_dir = common.scratch(f"pair_recipe/{name}_pair")
        common.occgt("pair", "--recipe", recipe, "--scene", line["scene"], "--frames", frames,
                     "--out", pair_dir, *extra)
        for m in PAIR_MEMBERS:
            if read(os.path.join(pair_dir, m)) != members[m]:
                fail(f"{tag}: occgt pair --recipe {m} differs from the shard's")
        # The score grid too: the recipe's selection.score_stride (it was 1 unless given).
        with open(os.path.join(pair_dir, "meta.json")) as f:
            meta = json.load(f)
        shard_json = json.loads(members["json"])
        for k in ("score_stride", "score_metrics"):
            if meta[k] != shard_json[k]:
                fail(f"{tag}: occgt pair --recipe meta.json {k} {meta[k]} against the shard's "
                     f"{shard_json[k]}")
        occ_dir = common.scratch(f"pair_recipe/{name}_occupancy")
        common.occgt("occupancy", "--recipe", recipe, "--scene", line["scene"], "--frames", frames,
                     "--dense", "--out", occ_dir, *extra)
        compared = 0
        for member, file in OCC_MEMBERS.items():
            if member in members:
                compared += 1
                if read(os.path.join(occ_dir, file)) != members[member]:
                    fail(f"{tag}: occgt occupancy --recipe {file} differs from the shard's {member}")
        if compared < 4:
            fail(f"{tag}: the shard has {compared} occupancy members")
        # One vocabulary: the sample json names the bin edges, the fusion statistics and the
        # voxel size as occupancy.json does, each once ("occupancy"."bins"."edges_m",
        # "occupancy"."fusion"."stats", and the options' "fusion"."voxel_m").
        sample = json.loads(members["json"])
        with open(os.path.join(occ_dir, "occupancy.json")) as f:
            occ_meta = json.load(f)
        if sample["occupancy"]["bins"] != {"edges_m": occ_meta["bins"]["edges_m"]}:
            fail(f"{tag}: the sample's occupancy.bins {sample['occupancy']['bins']} are not "
                 f"occupancy.json's bins.edges_m {occ_meta['bins']['edges_m']}")
        stats = occ_meta["fusion"]["stats"]
        if stats is not None:
            stats = {k: v for k, v in stats.items() if k != "leaf_nodes"}  # occupancy.json's only
        if sample["occupancy"]["fusion"] != {"stats": stats} or "fusion_stats" in sample["occupancy"]:
            fail(f"{tag}: the sample's occupancy.fusion {sample['occupancy'].get('fusion')} is "
                 f"not occupancy.json's fusion.stats {stats}")
        for c in ("counts0", "counts1"):  # occupancy.json adds the fractions
            if sample["occupancy"][c] != {k: occ_meta[c][k] for k in ("occupied", "free",
                                                                      "unknown")}:
                fail(f"{tag}: the sample's occupancy.{c} {sample['occupancy'][c]} against "
                     f"occupancy.json's {occ_meta[c]}")
        options = sample["occupancy_options"]
        if options["fusion"]["voxel_m"] != occ_meta["fusion"]["voxel_m"] or \
                "voxel_m" in sample["occupancy"]:
            fail(f"{tag}: voxel_m: sample {sample['occupancy']}, {options['fusion']}; "
                 f"occupancy.json {occ_meta['fusion']}")
        if {k: v for k, v in occ_meta["bins"].items() if k != "edges_m"} != options["bins"]:
            fail(f"{tag}: occupancy.json's bins {occ_meta['bins']} against the sample's "
                 f"occupancy_options.bins {options['bins']}")
        if occ_meta["files"][-2:] != ["occ0_dense.npy", "occ1_dense.npy"]:
            fail(f"{tag}: occupancy.json's files {occ_meta['files']}")
        print(f"{tag}: {len(PAIR_MEMBERS)} + {compared} arrays equal to the shard's")
    return lines[0]


def occupancy_json(*args):
    out = common.scratch("pair_recipe/override")
    common.occgt("occupancy", *args, "--out", out)
    with open(os.path.join(out, "occupancy.json")) as f:
        return json.load(f)


def run_cli_doc_example(tmp):
    """Runs the commands of docs/CLI.md "## pair and occupancy" as written (in a scratch
    folder that links recipes/), then checks the claim that follows them."""
    text = open(os.path.join(common.SOURCE, "docs", "CLI.md"), encoding="utf-8").read()
    section = re.search(r"^## pair and occupancy\n(.*?)(?=^## )", text, re.S | re.M).group(1)
    cmds = [l.strip() for l in section.splitlines() if l.startswith("    occgt ")
            and "[" not in l]
    if len(cmds) != 3:
        fail(f"docs/CLI.md pair and occupancy: expected 3 example commands, found {cmds}")
    cwd = common.scratch("pair_recipe/doc")
    os.symlink(os.path.join(common.SOURCE, "recipes"), os.path.join(cwd, "recipes"))
    for c in cmds:
        args = shlex.split(c)
        r = subprocess.run([common.BINARY, *args[1:]], cwd=cwd, capture_output=True, text=True)
        if r.returncode != 0:
            fail(f"docs/CLI.md example {c!r}: exit {r.returncode}: {r.stderr}")
    claim = re.search(r"equal the members of sample\n\s*# (\S+) in (\S+)", section)
    key, tar = claim.group(1), claim.group(2)
    members = shard_members(os.path.join(cwd, tar), key)
    for m in PAIR_MEMBERS + ["occ0.npy", "known0.npy", "occ1.npy", "known1.npy"]:
        if read(os.path.join(cwd, "out", "ta_pair", m)) != members[m]:
            fail(f"docs/CLI.md example: {m} differs from {key} in {tar}")
    print("docs/CLI.md pair and occupancy example: ok")


def main():
    tmp = common.scratch("pair_recipe")
    run_cli_doc_example(tmp)

    # The shipped TartanAir sample: far_m 20 is the last bin edge and the ray range.
    tartan = os.path.join(common.SOURCE, "recipes", "tartanair-sample.yaml")
    build = os.path.join(tmp, "tartanair")
    common.occgt("build", "--json", tartan, "--out", build)
    line = check_pairs("tartanair", tartan, build)

    # The shipped demo (synthetic: the data generated into DIR/data, read as generic).
    demo = os.path.join(common.SOURCE, "recipes", "demo.yaml")
    build_demo = os.path.join(tmp, "demo")
    common.occgt("build", "--json", demo, "--out", build_demo)
    check_pairs("demo", demo, build_demo, extra=("--root", os.path.join(build_demo, "data")))
    r = common.occgt("pair", "--recipe", demo, "--scene", "synth_000", "--frames", "000000,000001",
                     "--out", os.path.join(tmp, "no_root"), check=False)
    if r.returncode != 2 or not r.stderr.startswith("occgt: error: --root: "):
        fail(f"synthetic recipe without --root: exit {r.returncode}, {r.stderr!r}")

    # Non-default labels, patches, bins and a window scope; packed and dense volumes.
    data = os.path.join(tmp, "synth")
    common.occgt("synth", "--out", data, "--scenes", "1", "--frames", "10", "--resolution",
                 "256x192", "--seed", "3")
    recipe = os.path.join(tmp, "recipe.yaml")
    with open(recipe, "w") as f:
        f.write(SYNTH_RECIPE.format(root=data))
    build_synth = os.path.join(tmp, "synth_build")
    common.occgt("build", "--json", recipe, "--out", build_synth)
    check_pairs("synthetic", recipe, build_synth)
    meta = occupancy_json("--recipe", recipe, "--scene", "synth_000", "--frames", "000002,000004")
    if meta["fusion"]["scope"] != "window:1" or meta["fusion"]["fused_frames"] != [
            "000001", "000002", "000003", "000004", "000005"]:
        fail(f"the recipe's window scope not used: {meta['fusion']}")

    # --mutual / --no-mutual override the recipe's patches.mutual (false here) both ways.
    with open(os.path.join(build_synth, "pairs.jsonl")) as f:
        first = json.loads(f.readline())

    def pair_meta(*flags):
        out = common.scratch("pair_recipe/mutual")
        common.occgt("pair", "--recipe", recipe, "--scene", first["scene"], "--frames",
                     f"{first['frame0']['id']},{first['frame1']['id']}", *flags, "--out", out)
        meta = json.load(open(os.path.join(out, "meta.json")))
        return meta, meta["matches"]["vv"]
    (m_recipe, n_recipe), (m_on, n_on), (m_off, n_off) = (
        pair_meta(), pair_meta("--mutual"), pair_meta("--no-mutual"))
    got = [m["patch_options"]["mutual"] for m in (m_recipe, m_on, m_off)]
    if got != [False, True, False]:
        fail(f"patches.mutual with recipe / --mutual / --no-mutual: {got}")
    if not (n_on < n_recipe == n_off):
        fail(f"match counts recipe {n_recipe}, --mutual {n_on}, --no-mutual {n_off}")

    # Flags override single fields of the recipe; the ray range follows --far-m.
    frames = f"{line['frame0']['id']},{line['frame1']['id']}"
    meta = occupancy_json("--recipe", tartan, "--scene", line["scene"], "--frames", frames,
                          "--far-m", "12", "--bins", "16")
    if (meta["bins"]["far_m"], meta["fusion"]["max_range_m"]) != (12, 12):
        fail(f"--far-m 12 over the recipe: bins {meta['bins']}, fusion {meta['fusion']}")
    if meta["bins"]["num_bins"] != 16 or meta["fusion"]["voxel_m"] != 0.1:
        fail(f"--bins 16 over the recipe: bins {meta['bins']}, fusion {meta['fusion']}")
    if meta["fusion"]["max_depth_m"] != 100 or meta["resolution"] != [640, 480]:
        fail(f"the recipe's max_depth_m / resolution not kept: {meta}")
    # The old single-pair default (a 10 m ray range under far_m 20) does not give the shard.
    members = shard_members(os.path.join(build, line["shard"]), line["key"])
    out = common.scratch("pair_recipe/range10")
    common.occgt("occupancy", "--recipe", tartan, "--scene", line["scene"], "--frames", frames,
                 "--max-range-m", "10", "--out", out)
    if all(read(os.path.join(out, m)) == members[m] for m in ["occ0.npy", "known0.npy",
                                                             "occ1.npy", "known1.npy"]):
        fail("a 10 m ray range gives the shard's volumes too: the pair does not test the range")
    root = common.shared("tartanair/hospital_sample")
    plain = ("--root", root, "--format", "tartanair", "--scene", "hospital_sample", "--frames",
             frames)
    meta = occupancy_json(*plain, "--far-m", "20")
    if (meta["bins"]["far_m"], meta["fusion"]["max_range_m"]) != (20, 20):
        fail(f"--far-m 20 without a recipe: bins {meta['bins']}, fusion {meta['fusion']}")
    meta = occupancy_json(*plain, "--far-m", "20", "--max-range-m", "5")
    if (meta["bins"]["far_m"], meta["fusion"]["max_range_m"]) != (20, 5):
        fail(f"--max-range-m 5: bins {meta['bins']}, fusion {meta['fusion']}")
    meta = occupancy_json(*plain)
    if (meta["bins"]["far_m"], meta["fusion"]["max_range_m"], meta["fusion"]["voxel_m"],
            meta["bins"]["num_bins"]) != (10, 10, 0.05, 64):
        fail(f"defaults (a recipe without occupancy keys): {meta['bins']}, {meta['fusion']}")
    out = common.scratch("pair_recipe/pair_override")
    common.occgt("pair", "--recipe", tartan, "--scene", line["scene"], "--frames", frames,
                 "--stride", "16", "--preset", "occ2net", "--out", out)
    with open(os.path.join(out, "meta.json")) as f:
        pm = json.load(f)
    if json.dumps(pm).find('"occ2net"') < 0:
        fail("--preset occ2net over the recipe not recorded in meta.json")
    import numpy as np
    if np.load(os.path.join(out, "cells0.npy")).shape != (30, 40):
        fail("--stride 16 over the recipe: cells0 is not 30x40")
    r = common.occgt("occupancy", "--recipe", os.path.join(tmp, "missing.yaml"), "--scene", "s",
                     "--frames", "a,b", "--out", out, check=False)
    if r.returncode != 1 or "missing.yaml: recipe file not found" not in r.stderr:
        fail(f"missing recipe: exit {r.returncode}, {r.stderr!r}")
    print("pair/occupancy --recipe: ok")


if __name__ == "__main__":
    main()
