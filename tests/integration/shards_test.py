"""Shards as a trainer reads them: tarfile + NumPy grouping members by key, index.json
against schemas/index.schema.json with jsonschema, the LoFTR npz files with NumPy, and
the NumPy reader printed in docs/READING_SHARDS.md (executed verbatim).

The split is written by the gtest ShardsDemo.WriteDemoSplit (tests/shards/split_test.cc,
the libgt/shards writer on build-like samples) and merged with `occgt merge`; once
`occgt build` exists its own integration tests cover the same reading path.
"""
import hashlib
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

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common  # noqa: E402


def fail(msg):
    sys.exit("FAIL: " + msg)


def check(cond, msg):
    if not cond:
        fail(msg)


def write_demo_split():
    gtest = os.path.join(os.path.dirname(os.path.dirname(common.BINARY)), "tests",
                         "test_shards_split")
    check(os.path.exists(gtest), f"gtest binary missing (build test_shards_split): {gtest}")
    out = common.scratch("shards_demo")
    env = dict(os.environ, OCCGT_SHARDS_DEMO_OUT=out)
    r = subprocess.run([gtest, "--gtest_filter=ShardsDemo.*"], capture_output=True, text=True,
                       env=env)
    check(r.returncode == 0, f"{gtest} failed:\n{r.stdout}\n{r.stderr}")
    return out


def doc_reader():
    """Executes the NumPy reader block of docs/READING_SHARDS.md; returns its namespace."""
    with open(os.path.join(common.SOURCE, "docs", "READING_SHARDS.md")) as f:
        text = f.read()
    m = re.search(r"<!-- reader:numpy -->\s*```python\n(.*?)```\s*<!-- /reader:numpy -->", text,
                  re.S)
    check(m is not None, "docs/READING_SHARDS.md has no <!-- reader:numpy --> python block")
    namespace = {}
    exec(compile(m.group(1), "READING_SHARDS.md:reader", "exec"), namespace)
    return namespace


def group_by_key(tar_path):
    """Independent WebDataset-style grouping with tarfile (no code from the doc)."""
    samples = []
    with tarfile.open(tar_path, "r:") as tar:
        for member in tar.getmembers():
            check(member.isfile(), f"{member.name}: not a regular file")
            folder, _, base = member.name.rpartition("/")
            stem, _, field = base.partition(".")
            key = f"{folder}/{stem}"
            if not samples or samples[-1][0] != key:
                check(all(k != key for k, _ in samples), f"{key}: members not contiguous")
                samples.append((key, {}))
            samples[-1][1][field] = (member, tar.extractfile(member).read())
    return samples


def check_real_build():
    """`occgt build` of the demo recipe: validate passes with every schema of schemas/,
    a re-merge reproduces index.json and pairs.jsonl byte for byte and keeps the build's
    summary.json, and the doc reader reads the samples with the documented dtypes."""
    out = common.scratch("shards_build_demo")
    recipe, _, _ = common.demo_recipe(common.scratch("shards_build_demo_recipe"))
    common.occgt("build", "--json", recipe, "--out", out)
    schemas = os.path.join(common.SOURCE, "schemas")
    r = common.occgt("validate", "--schemas", schemas, out, check=False)
    check(r.returncode == 0, f"validate of a build output:\n{r.stdout}{r.stderr}")
    # Without --schemas, the copies built into occgt: every check runs from any folder.
    r = common.occgt("validate", out, check=False)
    check(r.returncode == 0, f"validate with the built-in schemas:\n{r.stdout}{r.stderr}")
    edited = os.path.join(common.scratch("shards_build_demo_edited"), "split")
    shutil.rmtree(os.path.dirname(edited))
    shutil.copytree(out, edited)
    with open(os.path.join(edited, "pairs.jsonl")) as f:
        lines = [json.loads(line) for line in f]
    lines[5]["score_metrics"]["01"]["overlap"] = "x"
    with open(os.path.join(edited, "pairs.jsonl"), "w") as f:
        f.write("".join(json.dumps(line) + "\n" for line in lines))
    r = common.occgt("validate", edited, check=False)
    check(r.returncode == 1 and "pairs.jsonl:6: pairs_line.schema.json: " in r.stdout,
          f"a schema violation found without --schemas:\n{r.stdout}{r.stderr}")
    empty = common.scratch("shards_schemas_empty")
    r = common.occgt("validate", "--schemas", empty, out, check=False)
    check(r.returncode == 1 and "index.schema.json: missing" in r.stdout,
          f"a --schemas folder without the schemas is a problem:\n{r.stdout}{r.stderr}")
    before = {f: open(os.path.join(out, f), "rb").read()
              for f in ("index.json", "pairs.jsonl", "summary.json")}
    common.occgt("merge", "--schemas", schemas, out)
    for f, data in before.items():
        check(open(os.path.join(out, f), "rb").read() == data, f"merge changed {f}")
    # A split without summary.json (assembled from task outputs): merge writes its own,
    # which follows summary.schema.json too (its merge branch).
    bare = os.path.join(common.scratch("shards_build_demo_bare"), "split")
    shutil.copytree(out, bare)
    for f in ("summary.json", "index.json", "pairs.jsonl"):
        os.remove(os.path.join(bare, f))
    common.occgt("merge", "--schemas", schemas, bare)
    with open(os.path.join(bare, "summary.json")) as f:
        merged = json.load(f)
    with open(os.path.join(schemas, "summary.schema.json")) as f:
        jsonschema.validate(merged, json.load(f), cls=jsonschema.Draft202012Validator)
    check(merged["kind"] == "occgt-merge-summary" and merged["samples"] == 24, str(merged))
    # Its report still lists the build's drops: summed over selection/*.json.
    common.occgt("inspect", "split", bare, "--gallery", 0)
    with open(os.path.join(bare, "inspect", "report.html")) as f:
        html = f.read()
    with open(os.path.join(out, "summary.json")) as f:
        drops = json.load(f)["drops"]
    check(bool(drops), "the demo build drops pairs")
    for reason, n in drops.items():
        check(f'<tr><td>{reason}</td><td class="n">{n}</td></tr>' in html,
              f"merged split's report: drop {reason} {n} missing")
    ns = doc_reader()
    n = 0
    for s in ns["iter_split"](out):
        n += 1
        lab = s["label01.npy"]
        check(lab.dtype == np.uint8 and lab.ndim == 2, f"{s['__key__']}: label01 {lab.dtype}")
        check(s["matches.npy"].dtype == np.int32 and s["matches.npy"].shape[1:] == (2,),
              f"{s['__key__']}: matches")
        check(s["json"]["key"] == s["__key__"], f"{s['__key__']}: json key")
    with open(os.path.join(out, "index.json")) as f:
        check(n == sum(e["nsamples"] for e in json.load(f)["shardlist"]) and n > 0,
              f"{n} samples read")


def main():
    out = write_demo_split()

    # index.json: schema, md5 and sizes recomputed here.
    with open(os.path.join(common.SOURCE, "schemas", "index.schema.json")) as f:
        schema = json.load(f)
    jsonschema.Draft202012Validator.check_schema(schema)
    with open(os.path.join(out, "index.json")) as f:
        index = json.load(f)
    jsonschema.Draft202012Validator(schema).validate(index)
    check(index["name"] == "train", "index name")
    total = 0
    keys_in_tars = []
    for entry in index["shardlist"]:
        path = os.path.join(out, entry["url"])
        with open(path, "rb") as f:
            data = f.read()
        check(hashlib.md5(data).hexdigest() == entry["md5sum"], f"{path}: md5")
        check(len(data) == entry["filesize"], f"{path}: filesize")
        check(len(data) % 512 == 0 and len(data) % 10240 != 0,
              f"{path}: size {len(data)} (expected 512-multiple, unpadded)")
        samples = group_by_key(path)
        check(len(samples) == entry["nsamples"], f"{path}: {len(samples)} samples")
        total += len(samples)
        for key, fields in samples:
            keys_in_tars.append((entry["url"], key))
            check("." not in key.rpartition("/")[2], f"{key}: dot in basename")
            for field, (member, payload) in fields.items():
                check(len(member.name) <= 100, f"{member.name}: > 100 bytes")
                check(member.mtime == 0 and member.uid == 0 and member.gid == 0,
                      f"{member.name}: mtime/uid/gid")
                check(member.mode == 0o644, f"{member.name}: mode {oct(member.mode)}")
                check(member.uname == "" and member.gname == "", f"{member.name}: owner names")
                header = data[member.offset:member.offset + 512]
                check(header[257:263] == b"ustar\0" and header[263:265] == b"00",
                      f"{member.name}: not a POSIX ustar header")
                if field.endswith(".npy"):
                    hlen = int.from_bytes(payload[8:10], "little")
                    check((member.offset_data + 10 + hlen) % 64 == 0,
                          f"{member.name}: array data not 64-byte aligned")
            # Fields, dtypes and shapes of the demo samples.
            meta = json.loads(fields["json"][1])
            check(key.startswith(meta["scene"].replace(".", "_")), f"{key}: scene {meta}")
            for name, dtype, shape in [("label01.npy", np.uint8, (12, 16)),
                                       ("label10.npy", np.uint8, (12, 16)),
                                       ("matches.npy", np.int32, (5, 2)),
                                       ("depth0.npy", np.float32, (12, 16))]:
                arr = np.load(io.BytesIO(fields[name][1]), allow_pickle=False)
                check(arr.dtype == dtype and arr.shape == shape,
                      f"{key}.{name}: {arr.dtype} {arr.shape}")
            check(fields["image0.png"][1][:8] == b"\x89PNG\r\n\x1a\n", f"{key}: png magic")
            labels = np.load(io.BytesIO(fields["label01.npy"][1]))
            check(labels.max() <= 5, f"{key}: label codes")

    # pairs.jsonl: one line per sample, same order, naming shard and key.
    with open(os.path.join(out, "pairs.jsonl")) as f:
        lines = [json.loads(line) for line in f]
    check(len(lines) == total == 11, f"{len(lines)} lines, {total} samples")
    check([(l["shard"], l["key"]) for l in lines] == keys_in_tars, "pairs.jsonl order/keys")

    # The reader printed in the docs gives the same samples.
    ns = doc_reader()
    from_doc = list(ns["iter_split"](out))
    check([s["__key__"] for s in from_doc] == [k for _, k in keys_in_tars], "doc reader keys")
    first = from_doc[0]
    check(first["label01.npy"].dtype == np.uint8 and first["label01.npy"].shape == (12, 16),
          "doc reader label01")
    check(isinstance(first["json"], dict) and first["json"]["scene"] == "scene0707_00",
          "doc reader json")

    # occgt validate: clean, then a flipped byte and a missing shard.
    # Only the index schema applies: the demo samples are not `occgt build` samples, so the
    # folder's sample and line schemas accept any document, and their values are not checked
    # (--structure-only; check_real_build validates a real build's).
    schemas = common.scratch("shards_schemas")
    shutil.copy(os.path.join(common.SOURCE, "schemas", "index.schema.json"), schemas)
    for name in ("sample", "views_sample", "pairs_line", "views_line"):
        with open(os.path.join(schemas, f"{name}.schema.json"), "w") as f:
            f.write("{}\n")
    r = common.occgt("validate", "--structure-only", "--schemas", schemas, out, check=False)
    check(r.returncode == 0, f"validate on a clean split: {r.stdout}{r.stderr}")
    bad = common.scratch("shards_demo_bad")
    shutil.rmtree(bad)
    shutil.copytree(out, bad)
    with open(os.path.join(bad, "train-000001.tar"), "r+b") as f:
        f.seek(600)
        byte = f.read(1)
        f.seek(600)
        f.write(bytes([byte[0] ^ 0x10]))
    os.remove(os.path.join(bad, "train-000002.tar"))
    r = common.occgt("validate", "--structure-only", "--schemas", schemas, bad, check=False)
    check(r.returncode == 1, f"validate exit code {r.returncode}")
    check("train-000001.tar: md5" in r.stdout, f"flipped byte not reported:\n{r.stdout}")
    check("train-000002.tar: missing shard" in r.stdout, f"missing shard not reported:\n{r.stdout}")
    # One line for the missing shard, not one more per pairs.jsonl line naming it.
    check("is not in shard" not in r.stdout and " lines for " not in r.stdout,
          f"lines of a shard already reported:\n{r.stdout}")

    # LoFTR export read with NumPy.
    loftr = os.path.join(out, "loftr")
    with open(os.path.join(loftr, "train_list.txt")) as f:
        listed = f.read().split()
    check(listed == ["hospital_Easy_P036.npz", "scene0707_00.npz"], f"list {listed}")
    d = np.load(os.path.join(loftr, "scene_data", "train", "scene0707_00.npz"))
    check(d["name"].dtype == np.int64 and d["name"].shape == (7, 4), f"name {d['name'].dtype}")
    check((d["name"][:, 0] == 707).all() and (d["name"][:, 1] == 0).all(), "scene numbers")
    check(d["score"].dtype == np.float32 and d["score"].shape == (7,), "score")
    intr = np.load(os.path.join(loftr, "intrinsics.npz"))
    # hospital/Easy/P036 also under scene0000_00, the folder LoFTR forms from its name rows.
    check(sorted(intr.keys()) == ["hospital/Easy/P036", "scene0000_00", "scene0707_00"],
          f"{list(intr.keys())}")
    check(np.array_equal(intr["scene0000_00"], intr["hospital/Easy/P036"]), "alias K")
    check(intr["scene0707_00"].dtype == np.float64 and intr["scene0707_00"].shape == (3, 3), "K")
    with open(os.path.join(loftr, "scenes.txt")) as f:
        check(f.read().split("\n")[0] == "hospital/Easy/P036", "scenes.txt")
    t = np.load(os.path.join(out, "loftr_test", "test.npz"))
    check(t["name"].dtype == np.uint16 and t["name"].shape == (11, 4), "test name")
    check(t["rel_pose"].dtype == np.float32 and t["rel_pose"].shape == (11, 12), "rel_pose")
    with open(os.path.join(out, "loftr_test", "statistics.json")) as f:
        check(json.load(f) == {"scene0707_00": 7, "hospital/Easy/P036": 4}, "statistics")
    check_real_build()
    print("ok: shards, index.json, pairs.jsonl, doc reader, validate, LoFTR export")


if __name__ == "__main__":
    main()
