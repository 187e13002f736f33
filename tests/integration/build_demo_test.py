"""occgt build on recipes/demo.yaml (synthetic data generated into <out>/data), read back
the way a trainer would: tarfile + numpy grouping members by key, every array's shape and
dtype, labels consistent with metrics, cells and matches; JSON validated against schemas/;
LoFTR test.npz read with numpy. Then: two runs give byte-identical shards, a deleted shard
is rebuilt by a re-run and nothing else is rewritten, a 2-task split gives the same files,
--dry-run writes nothing, and bad recipes fail before any work with one line.
Under a sanitizer the recipe is built at half its width and height (common.py)."""
import glob
import gzip
import io
import json
import os
import re
import shutil
import sys
import tarfile

import numpy as np
import jsonschema

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common  # noqa: E402

LABELS = {"NO_DEPTH": 0, "OUT_OF_VIEW": 1, "VISIBLE": 2, "OCCLUDED": 3, "INCONSISTENT": 4, "UNKNOWN": 5}


def schema(name):
    with open(os.path.join(common.SOURCE, "schemas", name)) as f:
        return json.load(f)


def validate(doc, name):
    jsonschema.validate(doc, schema(name), cls=jsonschema.Draft202012Validator)


def read_shard(path):
    """{key: {field: bytes}} in tar order, grouped the WebDataset way."""
    samples = {}
    order = []
    with tarfile.open(path) as tf:
        for m in tf:
            assert m.isfile(), m.name
            assert len(m.name.encode()) <= 100, m.name
            assert m.mtime == 0 and m.uid == 0 and m.gid == 0, m.name
            folder, base = os.path.split(m.name)
            stem, field = base.split(".", 1)
            key = f"{folder}/{stem}" if folder else stem
            if key not in samples:
                assert not order or order[-1] != key
                order.append(key)
                samples[key] = {}
            assert order[-1] == key, f"members of {key} not contiguous"
            data = tf.extractfile(m).read()
            # demo.yaml leaves sample.compression at its default, deflate: every array is a
            # .npy.gz member, a gzip with no name and mtime 0 (the same bytes on every run).
            assert not field.endswith(".npy"), f"{m.name}: plain .npy under the default"
            if field.endswith(".npy.gz"):
                assert data[:2] == b"\x1f\x8b" and data[3] == 0 and data[4:8] == bytes(4), m.name
                field, data = field[:-3], gzip.decompress(data)
            samples[key][field] = data
    return samples


def npy(b):
    return np.load(io.BytesIO(b), allow_pickle=False)


def check_sample(key, fields, width, height, stride=8):
    """Shapes, dtypes and cross-consistency of one sample; returns its metadata."""
    meta = json.loads(fields["json"])
    validate(meta, "sample.schema.json")
    assert meta["key"] == key
    assert "." not in key.rsplit("/", 1)[-1]
    assert meta["resolution"] == [width, height]
    l01 = npy(fields["label01.npy"])
    l10 = npy(fields["label10.npy"])
    for lab, d in ((l01, "01"), (l10, "10")):
        assert lab.dtype == np.uint8 and lab.shape == (height, width), (lab.dtype, lab.shape)
        assert lab.max() <= 5
        counts = meta["metrics"][d]["counts"]
        for name, code in LABELS.items():
            assert int((lab == code).sum()) == counts[name], (key, d, name)
        m = meta["metrics"][d]
        valid = lab.size - counts["NO_DEPTH"]
        assert m["valid"] == valid
        moved = counts["VISIBLE"] + counts["OCCLUDED"] + counts["INCONSISTENT"] + counts["UNKNOWN"]
        assert abs(m["overlap"] - (moved / valid if valid else 0.0)) < 1e-12
        assert abs(m["occlusion_ratio"] - counts["OCCLUDED"] / lab.size) < 1e-12
    matches = npy(fields["matches.npy"])
    mtype = npy(fields["match_type.npy"])
    mxy = npy(fields["match_xy.npy"])
    n = meta["matches"]["total"]
    assert matches.dtype == np.int32 and matches.shape == (n, 2)
    assert mtype.dtype == np.uint8 and mtype.shape == (n,)
    assert mxy.dtype == np.float32 and mxy.shape == (n, 2)
    for t, name in enumerate(("vv", "vo", "ov")):
        assert int((mtype == t).sum()) == meta["matches"][name]
    cw, ch = width // stride, height // stride
    c0 = npy(fields["cells0.npy"])
    c1 = npy(fields["cells1.npy"])
    assert c0.dtype == np.uint8 and c0.shape == (ch, cw)
    assert c1.shape == (ch, cw)
    # Centre anchors: the cell label is the label of pixel (s*c + s/2, s*r + s/2).
    a = np.arange(cw) * stride + stride // 2
    b = np.arange(ch) * stride + stride // 2
    assert np.array_equal(c0, l01[np.ix_(b, a)])
    assert np.array_equal(c1, l10[np.ix_(b, a)])
    assert matches.size == 0 or (matches.min() >= 0 and matches.max() < cw * ch)
    # vv and vo: the anchor of cell i in image 0 is VISIBLE / OCCLUDED; ov: anchor j of 1 OCCLUDED.
    flat0, flat1 = c0.reshape(-1), c1.reshape(-1)
    assert np.all(flat0[matches[mtype == 0, 0]] == 2)
    assert np.all(flat0[matches[mtype == 1, 0]] == 3)
    assert np.all(flat1[matches[mtype == 2, 1]] == 3)
    for c in ("0", "1"):
        occ = npy(fields[f"occ{c}.npy"])
        known = npy(fields[f"known{c}.npy"])
        assert occ.dtype == np.uint64 and occ.shape == (height // 2, width // 2)
        assert known.dtype == np.uint64 and known.shape == occ.shape
        assert not np.any(occ & ~known), "occupied bits outside known bits"
        counts = meta["occupancy"][f"counts{c}"]
        bits = np.unpackbits(occ.view(np.uint8)).sum()
        assert int(bits) == counts["occupied"]
    assert len(meta["occupancy"]["bins"]["edges_m"]) == 65
    for c in ("0", "1"):
        d = npy(fields[f"depth{c}.npy"])
        assert d.dtype == np.float32 and d.shape == (height, width)
    # Pixels without depth are NO_DEPTH and nothing else is.
    d0 = npy(fields["depth0.npy"])
    opts = meta["label_options"]
    invalid = ~((d0 > 0) & (d0 >= opts["min_depth_m"]) & (d0 <= opts["max_depth_m"]) & np.isfinite(d0))
    assert np.array_equal(invalid, l01 == 0)
    # T_0to1 = inv(world_from_cam1) @ world_from_cam0.
    w0 = np.array(meta["world_from_cam0"])
    w1 = np.array(meta["world_from_cam1"])
    assert np.allclose(np.array(meta["T_0to1"]), np.linalg.inv(w1) @ w0, atol=1e-9)
    if "image0.png" in fields:
        from PIL import Image
        for c in ("0", "1"):
            im = Image.open(io.BytesIO(fields[f"image{c}.png"]))
            assert im.size == (width, height) and im.mode == "RGB"
    return meta


def read_split(out, split, width, height, stride=8):
    """Reads index.json, every shard and pairs.jsonl; returns (keys in order, metas)."""
    with open(os.path.join(out, "index.json")) as f:
        index = json.load(f)
    validate(index, "index.schema.json")
    keys, metas = [], []
    for shard in index["shardlist"]:
        path = os.path.join(out, shard["url"])
        assert os.path.getsize(path) == shard["filesize"]
        samples = read_shard(path)
        assert len(samples) == shard["nsamples"]
        for key, fields in samples.items():
            metas.append(check_sample(key, fields, width, height, stride))
            keys.append(key)
    with open(os.path.join(out, "pairs.jsonl")) as f:
        lines = [json.loads(line) for line in f]
    assert [p["key"] for p in lines] == keys
    for p, m in zip(lines, metas):
        validate(p, "pairs_line.schema.json")
        assert p["scene"] == m["scene"] and p["metrics"] == m["metrics"]
    with open(os.path.join(out, "summary.json")) as f:
        summary = json.load(f)
    validate(summary, "summary.schema.json")
    assert summary["samples"] == len(keys) and summary["complete"]
    # recipe.json: the resolved recipe and its digest, which every sample json carries.
    with open(os.path.join(out, "recipe.json")) as f:
        resolved = json.load(f)
    validate(resolved, "recipe_json.schema.json")
    assert {m["options_digest"] for m in metas} == {resolved["options_digest"]}
    c = summary["counts"]
    drops = summary["drops"]
    # Drop counts add up stage by stage.
    assert c["frames_total"] == c["frames_kept"] + sum(v for k, v in drops.items() if k.startswith("scan."))
    assert c["candidates"] == c["after_pruning"] + sum(v for k, v in drops.items() if k.startswith("prune."))
    assert c["scored"] == c["selected"] + sum(v for k, v in drops.items()
                                              if k.startswith(("filter.", "sample.")))
    return keys, metas, lines, summary


def tree_state(out):
    """{relative path: (inode, mtime_ns)} of every file."""
    state = {}
    for path in glob.glob(os.path.join(out, "**"), recursive=True):
        if os.path.isfile(path):
            st = os.stat(path)
            state[os.path.relpath(path, out)] = (st.st_ino, st.st_mtime_ns)
    return state


def file_bytes(out, pattern):
    return {os.path.basename(p): open(p, "rb").read() for p in sorted(glob.glob(os.path.join(out, pattern)))
            if os.path.isfile(p)}


def main():
    import yaml
    root = common.scratch("build_demo")
    recipe, width, height = common.demo_recipe(root)  # half size under a sanitizer
    out = os.path.join(root, "a")
    r = common.occgt("build", "--json", recipe, "--out", out)
    summary_stdout = json.loads(r.stdout)
    validate(summary_stdout, "summary.schema.json")
    assert "[write]" in r.stderr and "[select]" in r.stderr
    keys, metas, lines, summary = read_split(out, "demo", width, height)
    assert len(keys) == 24, len(keys)  # 2 scenes, quota 12
    assert summary["pairs_per_scene"] == {"synth_000": 12, "synth_001": 12}
    # selected_overlap: of the pairs' score_metrics with the recipe's aggregate (mean); the
    # median numpy's (24 pairs: the mean of the two middle values; it was the upper one).
    overlaps = np.array([0.5 * (l["score_metrics"]["01"]["overlap"] +
                                l["score_metrics"]["10"]["overlap"]) for l in lines])
    st = summary["selected_overlap"]
    assert np.isclose(st["median"], np.median(overlaps), rtol=0, atol=1e-12), (st, overlaps)
    assert np.isclose(st["mean"], overlaps.mean(), rtol=0, atol=1e-12), st
    assert (st["min"], st["max"]) == (overlaps.min(), overlaps.max()), st
    # The size estimate behind shards.target_mb errs on the large side for the synthetic
    # depth too (it counted it at sensor depth's deflate ratio: the demo's shards were 1.2x
    # the estimate, over a target), as build_samples checks on the real samples.
    with open(os.path.join(out, "index.json")) as f:
        actual = sum(s["filesize"] for s in json.load(f)["shardlist"])
    assert 0.5 <= actual / summary_stdout["estimated_bytes"] <= 1.0, \
        (actual, summary_stdout["estimated_bytes"])
    with open(os.path.join(out, "recipe.json")) as f:
        resolved = json.load(f)  # the demo's exports, recorded (and so in the digest)
    assert resolved["loftr_export"] == "test" and resolved["loftr_tree"] is True, resolved
    assert resolved["gluefactory_export"] is True and resolved["dust3r_export"] is True, resolved
    for p in lines:
        ov = (p["score_metrics"]["01"]["overlap"] + p["score_metrics"]["10"]["overlap"]) / 2
        assert 0.3 <= ov <= 0.95
    # LoFTR test export read with numpy.
    t = np.load(os.path.join(out, "loftr", "test.npz"))
    assert t["name"].shape == (24, 4) and t["rel_pose"].shape == (24, 12)
    for row, p in zip(t["rel_pose"], lines):
        assert np.allclose(row.reshape(3, 4), np.array(p["T_0to1"])[:3], atol=1e-5)
    assert [int(x) for x in t["name"][:, 2]] == [p["frame0"]["number"] for p in lines]
    # Export folders deleted after a complete build are written again by a re-run (it
    # printed "nothing to write" and left them missing), with the same bytes.
    exported = {f: file_bytes(out, f) for f in ("loftr/test.npz", "gluefactory/export.json")}
    shutil.rmtree(os.path.join(out, "loftr"))
    shutil.rmtree(os.path.join(out, "gluefactory"))
    common.occgt("build", recipe, "--out", out)
    for f, data in exported.items():
        assert file_bytes(out, f) == data, f"{f} not restored as it was"
    # So are a deleted pairs.jsonl and a deleted top file of the LoFTR export (they stayed
    # missing while the re-run printed "nothing to write").
    published = {f: file_bytes(out, f) for f in ("pairs.jsonl", "loftr/test.npz",
                                                 "loftr/intrinsics.npz")}
    for f in published:
        os.remove(os.path.join(out, f))
        common.occgt("build", recipe, "--out", out)
        assert file_bytes(out, f) == published[f], f"{f} not restored as it was"

    # LoFTR train export (ScanNet style) of the same recipe: names and overlap scores.
    with open(recipe) as f:
        doc = yaml.safe_load(f)
    doc["loftr_export"] = {"kind": "train"}
    doc["sample"]["depth"] = False
    train_recipe = os.path.join(root, "demo-train.yaml")
    with open(train_recipe, "w") as f:
        yaml.safe_dump(doc, f)
    out_t = os.path.join(root, "train")
    common.occgt("build", "--json", train_recipe, "--out", out_t)
    with open(os.path.join(out_t, "pairs.jsonl")) as f:
        tlines = [json.loads(line) for line in f]
    with open(os.path.join(out_t, "loftr", "scenes.txt")) as f:
        scene_names = f.read().split()
    rows = []
    for npz in sorted(glob.glob(os.path.join(out_t, "loftr", "scene_data", "demo", "*.npz"))):
        z = np.load(npz)
        assert z["name"].shape[1] == 4 and z["score"].dtype == np.float32
        for name, score in zip(z["name"], z["score"]):
            rows.append((scene_names[int(name[0])], int(name[2]), int(name[3]), float(score)))
    assert len(rows) == len(tlines) == 24
    for (scene, f0, f1, score), p in zip(rows, tlines):
        assert (scene, f0, f1) == (p["scene"], p["frame0"]["number"], p["frame1"]["number"])
        sm = p["score_metrics"]
        assert abs(score - (sm["01"]["overlap"] + sm["10"]["overlap"]) / 2) < 1e-6
    intr = np.load(os.path.join(out_t, "loftr", "intrinsics.npz"))
    assert intr[intr.files[0]].shape == (3, 3)

    # Determinism: a second run in another folder gives byte-identical outputs.
    out_b = os.path.join(root, "b")
    common.occgt("build", "--json", recipe, "--out", out_b, "--threads", "1")
    for pattern in ("*.tar", "index.json", "pairs.jsonl", "selection/*", "loftr/*"):
        a, b = file_bytes(out, pattern), file_bytes(out_b, pattern)
        assert a and a == b, pattern
    # The glue-factory and DUSt3R exports too, every file by its relative path.
    for export in ("gluefactory", "dust3r"):
        trees = []
        for o in (out, out_b):
            top = os.path.join(o, export)
            trees.append({os.path.relpath(os.path.join(d, n), top): open(os.path.join(d, n), "rb").read()
                          for d, _, names in os.walk(top) for n in names})
        assert trees[0] and trees[0] == trees[1], export

    # Re-run: nothing rewritten; a deleted shard is rebuilt, nothing else rewritten.
    before = tree_state(out)
    r = common.occgt("build", "--json", recipe, "--out", out)
    s2 = json.loads(r.stdout)
    assert s2["shards_written_this_run"] == 0 and s2["scenes_reused"] == 2
    assert tree_state(out) == before, "a re-run with nothing to do rewrote files"
    victim = os.path.join(out, "demo-000001.tar")
    victim_bytes = open(victim, "rb").read()
    os.remove(victim)
    before = tree_state(out)
    r = common.occgt("build", "--json", recipe, "--out", out)
    assert json.loads(r.stdout)["shards_written_this_run"] == 1
    # Progress counts what was found complete as resumed, once, and rates this run's work
    # only: both scenes' selections and shards 0 and 2 (16 pairs) were there.
    lines = [l for l in r.stderr.splitlines() if l.startswith("[")]
    assert [re.sub(r" [0-9.]+/s ETA \d+s$", "", l) for l in lines] == [
        "[select] 1/2 scenes (1 resumed)", "[select] 2/2 scenes (2 resumed)",
        "[write] 16/24 pairs (16 resumed)", "[write] 24/24 pairs (16 resumed)"], lines
    assert lines[2].endswith(" 0.00/s ETA 0s"), lines
    after = tree_state(out)
    assert open(victim, "rb").read() == victim_bytes
    for k, v in before.items():
        if k.endswith(".tar") or k.startswith(("selection/", "data/")):
            assert after[k] == v, f"{k} was rewritten"

    # Two tasks, select then write, give the same files as one run.
    out_c = os.path.join(root, "c")
    for stage in ("select", "write"):
        for task in ("1", "0"):
            common.occgt("build", "--json", recipe, "--out", out_c, "--tasks", "2", "--task", task, "--stage", stage)
    for pattern in ("*.tar", "index.json", "pairs.jsonl", "selection/*"):
        assert file_bytes(out, pattern) == file_bytes(out_c, pattern), pattern

    # Write before every selection exists: refused.
    out_d = os.path.join(root, "d")
    r = common.occgt("build", recipe, "--out", out_d, "--tasks", "2", "--task", "0", "--stage", "select")
    # The text counts the scenes selected so far, not every scene of the split.
    assert re.search(r": selected \d+ pairs? in 1 of 2 scenes so far \(1 scene this run\); the "
                     r"select stage writes no shard: run --stage write once every task has "
                     r"selected", r.stdout), r.stdout
    r = common.occgt("build", "--json", recipe, "--out", out_d, "--stage", "write", check=False)
    assert r.returncode == 1 and "selection: 1 of 2 scenes has no selection yet (synth_001): " \
        "the write stage selects nothing: run --stage select for every task" in r.stderr, r.stderr
    # More tasks than scenes, or than shards: a task that owns none says so (it said "0 scenes
    # this run" and "every shard of this task was complete already").
    out_t = os.path.join(root, "e_tasks")
    for task in range(5):
        common.occgt("build", recipe, "--out", out_t, "--tasks", "5", "--task", str(task),
                     "--stage", "select")
    r = common.occgt("build", recipe, "--out", out_t, "--tasks", "5", "--task", "4", "--stage",
                     "select")
    assert "(task 4 of 5 owns none of the scenes)" in r.stdout, r.stdout
    r = common.occgt("build", recipe, "--out", out_t, "--tasks", "5", "--task", "4", "--stage",
                     "write")
    assert "nothing to write: task 4 of 5 owns none of the shards" in r.stdout, r.stdout

    # Dry run: plan and statistics, no shards, nothing written except the synthetic data.
    out_e = os.path.join(root, "e")
    common.occgt("build", "--json", recipe, "--out", out_e)  # dataset + outputs
    shutil.rmtree(os.path.join(out_e, "selection"))
    for p in glob.glob(os.path.join(out_e, "*.tar")) + glob.glob(os.path.join(out_e, "*.json*")):
        os.remove(p)
    shutil.rmtree(os.path.join(out_e, "parts"))
    r = common.occgt("build", "--json", recipe, "--out", out_e, "--dry-run")
    s = json.loads(r.stdout)
    assert s["dry_run"] and s["samples"] == 24 and s["shards_planned"] == 3
    assert not glob.glob(os.path.join(out_e, "*.tar")) and not os.path.exists(os.path.join(out_e, "selection"))
    # The text says what is not written (it said "nothing written" while the folder gets its
    # lock file and a synthetic recipe its data).
    text = common.occgt("build", recipe, "--out", out_e, "--dry-run").stdout
    assert re.search(r": dry run: 24 pairs in 2 scenes would be written as 3 shards, about .*; "
                     r"no selection, shard or index written \(\d+\.\d s\)$", text.splitlines()[0]), text

    # A recipe that selects no pair publishes an empty split with every export (the LoFTR
    # export's intrinsics.npz without members used to fail: libzip writes no empty archive).
    with open(recipe) as f:
        doc = yaml.safe_load(f)
    doc["selection"]["overlap"] = [0.99, 1.0]
    none_recipe = os.path.join(root, "demo-none.yaml")
    with open(none_recipe, "w") as f:
        yaml.safe_dump(doc, f)
    out_n = os.path.join(root, "none")
    r = common.occgt("build", "--json", none_recipe, "--out", out_n)
    s = json.loads(r.stdout)
    validate(s, "summary.schema.json")
    assert s["samples"] == 0 and s["shards_planned"] == 0 and s["drops"]["filter.overlap"] > 0, s
    with open(os.path.join(out_n, "index.json")) as f:
        assert json.load(f)["shardlist"] == []
    t = np.load(os.path.join(out_n, "loftr", "test.npz"))
    assert t["name"].shape == (0, 4) and t["rel_pose"].shape == (0, 12)
    assert np.load(os.path.join(out_n, "loftr", "intrinsics.npz")).files == []
    for export in ("gluefactory/export.json", "dust3r/export.json", "loftr/tree.json"):
        assert os.path.isfile(os.path.join(out_n, export)), export
    r = common.occgt("build", none_recipe, "--out", out_n)
    assert "no pair passed the selection" in r.stdout, r.stdout
    common.occgt("validate", out_n)
    # The LoFTR export's top files deleted are restored by a re-run, as they were (the list
    # file and tree.json were not checked, so they stayed missing).
    for top in ("loftr/test_list.txt", "loftr/tree.json"):
        kept = file_bytes(out_n, top)
        os.remove(os.path.join(out_n, top))
        common.occgt("build", none_recipe, "--out", out_n)
        assert file_bytes(out_n, top) == kept, top
    # Another recipe into a built folder is refused, naming both digests; a dry run of it
    # there previews it (it was refused too) and changes nothing.
    before = {f: file_bytes(out, f) for f in ("recipe.json", "index.json", "summary.json")}
    r = common.occgt("build", none_recipe, "--out", out, check=False)
    assert r.returncode == 2 and "holds outputs of another recipe" in r.stderr and \
        "this recipe's" in r.stderr and "--dry-run previews it here" in r.stderr, r.stderr
    s = json.loads(common.occgt("build", "--json", none_recipe, "--out", out,
                                "--dry-run").stdout)
    assert s["dry_run"] and s["samples"] == 0 and s["scenes_reused"] == 0, s
    assert {f: file_bytes(out, f) for f in before} == before
    # A mesh depth source on scenes without a mesh: one line naming the scene, exit 1, no
    # selection saved (it published an empty split, exit 0, every frame a scan.read_error,
    # and kept that selection when the recipe was fixed and run again).
    nomesh = os.path.join(root, "nomesh")
    r = common.occgt("build", recipe, "--out", nomesh, "--depth-source", "mesh", check=False)
    assert r.returncode == 1, (r.returncode, r.stderr)
    assert r.stderr == ("occgt: error: synth_000: dataset.depth_source mesh needs the scene's "
                        "mesh, and it has none (set dataset.mesh_path, or use --depth-source "
                        "sensor)\n"), r.stderr
    assert not os.path.exists(os.path.join(nomesh, "selection", "synth_000.jsonl"))
    assert not os.path.exists(os.path.join(nomesh, "index.json"))
    # A mesh that cannot be parsed, or whose triangles name missing vertices: the same, one
    # line naming the mesh file (every frame was a scan.read_error, exit 0, and the empty
    # selection was kept after the mesh was mended). covis stops the same way.
    for name, text in (("cut.ply", "ply\nformat ascii 1.0\nelement vertex 3\n"),
                       ("bad_index.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty "
                        "float x\nproperty float y\nproperty float z\nelement face 1\nproperty "
                        "list uchar int vertex_indices\nend_header\n0 0 1\n1 0 1\n0 1 1\n"
                        "3 0 1 7\n")):
        mesh = os.path.join(root, name)
        with open(mesh, "w") as f:
            f.write(text)
        with open(recipe) as f:
            doc = yaml.safe_load(f)
        doc["dataset"].update(depth_source="mesh", mesh_path=mesh)
        mesh_recipe = os.path.join(root, "demo-" + name + ".yaml")
        with open(mesh_recipe, "w") as f:
            yaml.safe_dump(doc, f)
        badmesh = os.path.join(root, "badmesh_" + name)
        for command in ("build", "covis"):
            r = common.occgt(command, mesh_recipe, "--out", badmesh, check=False)
            assert r.returncode == 1 and r.stderr.startswith(f"occgt: error: {mesh}: ") and \
                r.stderr.count("\n") == 1, (command, r.returncode, r.stderr)
        assert "vertex index 7" in r.stderr or name == "cut.ply", r.stderr
        assert not os.path.exists(os.path.join(badmesh, "selection", "synth_000.jsonl"))
        assert not os.path.exists(os.path.join(badmesh, "covisibility", "synth_000.npz"))

    # Bad recipes: one line naming the file and field, exit 1, nothing created.
    bad_dir = common.scratch("build_demo_bad")
    cases = {
        "unknown.yaml": ("name: x\ndataset: {format: synthetic}\nselection: {overlapp: [0.1, 0.2]}\n",
                         "selection.overlapp: unknown key"),
        "type.yaml": ("name: x\ndataset: {format: synthetic}\nselection: {overlap: high}\n",
                      "selection.overlap: expected [lo, hi] with 0 <= lo <= hi <= 1"),
        "nodata.yaml": ("name: x\nseed: 1\n", "dataset: missing (required)"),
        "noroot.yaml": ("name: x\ndataset: {format: sevenscenes, root: nowhere}\n",
                        "dataset.root: expected an existing folder"),
    }
    for name, (text, expected) in cases.items():
        path = os.path.join(bad_dir, name)
        with open(path, "w") as f:
            f.write(text)
        out_bad = os.path.join(bad_dir, "out-" + name)
        r = common.occgt("build", "--json", path, "--out", out_bad, check=False)
        assert r.returncode == 1, (name, r.returncode)
        lines_err = r.stderr.strip().splitlines()
        assert len(lines_err) == 1 and lines_err[0].startswith(f"occgt: error: {path}: {expected}"), r.stderr
        assert not os.path.exists(out_bad), f"{name}: output created before validation"
    print("build_demo: 1 passed, 0 failed")


if __name__ == "__main__":
    main()
