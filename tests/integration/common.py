"""Shared helpers for the Python integration tests (run with Debian's /usr/bin/python3)."""
import os
import shutil
import subprocess
import sys

BINARY = os.environ.get("OCCGT_BINARY", "")
SHARED = os.environ.get("OCCGT_SHARED_DATA", "")
SOURCE = os.environ.get("OCCGT_SOURCE_DIR", "")
SCRATCH = os.environ.get("OCCGT_SCRATCH", "/tmp/occgt-scratch")
# "asan" or "tsan" when scripts/test-sanitize runs the test (it exports OCCGT_SANITIZER),
# "" otherwise. The tests that run many builds then build their recipes at half the width
# and height (half_size_when_sanitized): the same code paths, threads, file layout and
# checks on a quarter of the pixels, which is what keeps the sanitizer stages of CI short
# (docs/RELIABILITY.md "CI time").
SANITIZER = os.environ.get("OCCGT_SANITIZER", "")


def half_size_when_sanitized(doc):
    """Under a sanitizer, halves a recipe's working resolution (and a synthetic dataset's
    image size, which must match it); returns the recipe's (width, height) either way."""
    if SANITIZER:
        doc["resolution"] = [doc["resolution"][0] // 2, doc["resolution"][1] // 2]
        synthetic = doc.get("dataset", {}).get("synthetic")
        if synthetic is not None:
            synthetic["width"], synthetic["height"] = doc["resolution"]
    return tuple(doc["resolution"])


def demo_recipe(folder):
    """recipes/demo.yaml, or under a sanitizer a half-size copy of it written into folder
    (half_size_when_sanitized); returns (recipe path, width, height)."""
    import yaml
    recipe = os.path.join(SOURCE, "recipes", "demo.yaml")
    with open(recipe) as f:
        doc = yaml.safe_load(f)
    width, height = half_size_when_sanitized(doc)
    if SANITIZER:
        os.makedirs(folder, exist_ok=True)
        recipe = os.path.join(folder, "demo-half.yaml")
        with open(recipe, "w") as f:
            yaml.safe_dump(doc, f)
    return recipe, width, height


def shared(rel):
    """Path under ../shared/data; fails loudly when the real samples are missing."""
    p = os.path.join(SHARED, rel)
    if not os.path.exists(p):
        sys.exit(f"FAIL: real sample data missing: {p}")
    return p


def scratch(name):
    p = os.path.join(SCRATCH, name)
    shutil.rmtree(p, ignore_errors=True)
    os.makedirs(p)
    return p


def occgt(*args, check=True, env=None):
    """Runs the occgt binary; returns CompletedProcess with text stdout/stderr."""
    r = subprocess.run([BINARY, *map(str, args)], capture_output=True, text=True, env=env)
    if check and r.returncode != 0:
        raise AssertionError(f"occgt {' '.join(map(str, args))} failed ({r.returncode}):\n{r.stderr}")
    return r


# Keys of an `occgt build` summary that depend on the run (task layout, what this run
# wrote, timings); every other key must be equal between any two runs of one recipe.
RUN_SUMMARY_KEYS = {"task", "tasks", "stage", "timings", "bytes_written", "scenes_selected_this_run",
                    "scenes_reused", "shards_written_this_run", "shards_skipped_complete",
                    "samples_written_this_run"}


def stable_summary(path):
    """summary.json of a build without the keys of RUN_SUMMARY_KEYS."""
    import json
    with open(path) as f:
        doc = json.load(f)
    return {k: v for k, v in doc.items() if k not in RUN_SUMMARY_KEYS}


def tree_files(root, skip_dirs=()):
    """Sorted relative paths of every file under root, minus the folders in skip_dirs."""
    out = []
    for folder, dirs, files in os.walk(root):
        rel = os.path.relpath(folder, root)
        dirs[:] = [d for d in dirs if os.path.normpath(os.path.join(rel, d)) not in skip_dirs]
        out += [os.path.normpath(os.path.join(rel, f)) for f in files]
    return sorted(out)


def assert_same_outputs(ref, out, skip_dirs=()):
    """Same files under ref and out, byte for byte (summary.json: its stable keys).
    Returns the number of files compared."""
    a, b = tree_files(ref, skip_dirs), tree_files(out, skip_dirs)
    assert a == b, f"file lists differ: only in {ref}: {sorted(set(a) - set(b))}, " \
                   f"only in {out}: {sorted(set(b) - set(a))}"
    assert any(p.endswith(".tar") for p in a), f"no shard under {ref}"
    for rel in a:
        if rel == "summary.json":
            sa, sb = stable_summary(os.path.join(ref, rel)), stable_summary(os.path.join(out, rel))
            assert sa == sb, f"summary.json differs: {sa} vs {sb}"
            continue
        with open(os.path.join(ref, rel), "rb") as fa, open(os.path.join(out, rel), "rb") as fb:
            assert fa.read() == fb.read(), f"{rel} differs between {ref} and {out}"
    return len(a)


def tmp_files(root):
    """Leftover temporary files (*.tmp) anywhere under root."""
    return [p for p in tree_files(root) if p.endswith(".tmp") or ".tmp." in os.path.basename(p)]


def edit_first_sample_member(tar_path, field, edit):
    """Rewrites member `field` (its plain name: "label01.npy", "json") of the first sample of
    the shard `tar_path` as edit(bytes) -> bytes, keeping its compression (.gz or not), and
    records the shard's new size and MD5 in the index.json beside it, so that only the values
    are wrong. Returns the sample's key."""
    import gzip
    import hashlib
    import io
    import json
    import tarfile

    with tarfile.open(tar_path) as t:
        members = [(m, t.extractfile(m).read()) for m in t.getmembers()]
    key = members[0][0].name.split(".", 1)[0]
    out = io.BytesIO()
    with tarfile.open(fileobj=out, mode="w", format=tarfile.USTAR_FORMAT) as t:
        for m, data in members:
            name_key, name_field = m.name.split(".", 1)
            if name_key == key and name_field.removesuffix(".gz") == field:
                gz = name_field.endswith(".gz")
                data = edit(gzip.decompress(data) if gz else data)
                data = gzip.compress(data, mtime=0) if gz else data
                m.size = len(data)
            t.addfile(m, io.BytesIO(data))
    with open(tar_path, "wb") as f:
        f.write(out.getvalue())
    index_path = os.path.join(os.path.dirname(tar_path), "index.json")
    with open(index_path) as f:
        index = json.load(f)
    for e in index["shardlist"]:
        if e["url"] == os.path.basename(tar_path):
            e["filesize"] = len(out.getvalue())
            e["md5sum"] = hashlib.md5(out.getvalue()).hexdigest()
    with open(index_path, "w") as f:
        json.dump(index, f)
    return key
