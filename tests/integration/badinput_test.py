"""The bad-input corpus (tests/badinput/): every case of tests/badinput/cases.json is built
from a small valid input in a scratch folder (tests/badinput/generators.py), run through
the real `occgt` binary, and checked:

- fatal cases: the documented exit code (1), exactly ONE line on stderr,
  `occgt: error: <where>: <problem>`, matching the case's regex (which names the file,
  field or argument and the problem); no traceback-like or bad_alloc text;
- per-frame cases: exit 0 and the frame counted as skipped with its reason
  (`occgt scan --json` unusable_reasons, where it is in the input: unusable_examples'
  details, or the drops of the `occgt build` summary);
- validate cases: exit 1, the problem on a stdout line, one error line on stderr;
- always: no `*.tmp` left anywhere in the case folder, and no published partial output
  (per case: nothing published, or only complete shards with their part records).

Then the escape checks of issue 8 item 4 that need more than one command (tar member
names of a build over hostile scene folder names, a symlinked --out).
Run: ctest -R integration/badinput (OCCGT_BINARY etc. from tests/integration/CMakeLists.txt).
"""
import json
import os
import re
import resource
import shutil
import subprocess
import sys
import tarfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common  # noqa: E402

CORPUS = os.path.join(common.SOURCE, "tests", "badinput")
sys.path.insert(0, CORPUS)
import generators  # noqa: E402

PROGRESS = re.compile(r"^\[(select|write|index|merge)\]")
FAILURES = []


def fail(case_id, msg):
    FAILURES.append(f"{case_id}: {msg}")
    print(f"FAIL {case_id}: {msg}", flush=True)


def run(args, fsize_kb=None, timeout=120):
    def limit():
        if fsize_kb is not None:
            resource.setrlimit(resource.RLIMIT_FSIZE, (fsize_kb * 1024, fsize_kb * 1024))
    t0 = time.monotonic()
    r = subprocess.run([common.BINARY, *args], capture_output=True, text=True, timeout=timeout,
                       preexec_fn=limit if fsize_kb is not None else None)
    return r, time.monotonic() - t0


def stderr_lines(r):
    return [l for l in r.stderr.splitlines() if l.strip() and not PROGRESS.match(l)]


def tmp_files(folder):
    out = []
    for dirpath, dirnames, filenames in os.walk(folder):
        for n in dirnames + filenames:
            if n.endswith(".tmp"):
                out.append(os.path.join(dirpath, n))
    return out


PUBLISHED = ("index.json", "pairs.jsonl", "summary.json")


def check_outputs(case_id, out, mode):
    if mode == "any" or not os.path.isdir(out):
        return
    names = sorted(os.listdir(out))
    tars = [n for n in names if n.endswith(".tar")]
    if mode == "none":
        published = [n for n in names if n in PUBLISHED] + tars
        if published:
            fail(case_id, f"published output after a failure: {published}")
    elif mode == "complete":
        for t in tars:
            rec = os.path.join(out, "parts", t[:-4] + ".json")
            if not os.path.exists(rec):
                fail(case_id, f"{t} published without its part record")
                continue
            with open(rec) as f:
                size = json.load(f)["filesize"]
            if size != os.path.getsize(os.path.join(out, t)):
                fail(case_id, f"{t} size differs from its part record")
        for n in PUBLISHED:
            if n in names:
                fail(case_id, f"{n} published although the build failed")


def lookup(doc, path):
    for p in path:
        doc = doc[p]
    return doc


def check_case(spec, case_dir):
    cid = spec["id"]
    expect = spec["expect"]
    subst = {"case": case_dir, "data": os.path.join(case_dir, "data"),
             "out": os.path.join(case_dir, "out"), "recipe": os.path.join(case_dir, "recipe.yaml")}
    args = [a.format(**subst) for a in spec["cmd"]]
    try:
        r, seconds = run(args, fsize_kb=spec.get("fsize_kb"), timeout=spec.get("timeout", 120))
    except subprocess.TimeoutExpired:
        fail(cid, f"timed out: occgt {' '.join(args)}")
        return
    lines = stderr_lines(r)
    shown = f"\n  $ occgt {' '.join(args)}\n  exit {r.returncode}\n  stderr: {lines}"
    kind = expect["kind"]
    if "max_seconds" in expect and seconds > expect["max_seconds"]:
        fail(cid, f"took {seconds:.1f}s, expected a fast failure (< {expect['max_seconds']}s)")
    if kind == "fatal":
        if r.returncode != expect.get("exit", 1):
            fail(cid, f"expected exit {expect.get('exit', 1)}{shown}")
            return
        if len(lines) != 1:
            fail(cid, f"expected exactly one line on stderr{shown}")
            return
        line = lines[0]
        if not line.startswith("occgt: error: "):
            fail(cid, f"stderr line does not start with 'occgt: error: '{shown}")
        if re.search(r"bad_alloc|std::|terminate|Assertion|what\(\)", line):
            fail(cid, f"stderr line leaks an internal error{shown}")
        if not re.search(expect["line"], line):
            fail(cid, f"stderr line does not match /{expect['line']}/{shown}")
    elif kind in ("skipped", "drops", "ok"):
        if r.returncode != 0:
            fail(cid, f"expected exit 0{shown}")
            return
        if any("error" in l for l in lines):
            fail(cid, f"error text on stderr{shown}")
        if kind != "ok":
            try:
                doc = json.loads(r.stdout)
            except ValueError:
                fail(cid, f"stdout is not one JSON document{shown}")
                return
        if kind == "skipped":
            reasons = doc["totals"]["unusable_reasons"]
            for pattern, count in expect["reasons"].items():
                got = sum(n for k, n in reasons.items() if re.search(pattern, k))
                if got != count:
                    fail(cid, f"expected {count} frame(s) skipped for /{pattern}/, got {reasons}")
            details = [x["detail"] for s in doc["scenes"]
                       for examples in s["unusable_examples"].values() for x in examples]
            for pattern in expect.get("details", []):
                if not any(re.search(pattern, d) for d in details):
                    fail(cid, f"no unusable frame's detail matches /{pattern}/: {details}")
            if "unusable" in expect and doc["totals"]["unusable"] != expect["unusable"]:
                fail(cid, f"expected {expect['unusable']} unusable frames, got {doc['totals']}")
            if "depth_errors" in expect:
                errors = [e for s in doc["scenes"] for e in ((s.get("depth_check") or {}).get("errors") or [])]
                if not any(re.search(expect["depth_errors"], e) for e in errors):
                    fail(cid, f"no depth-check message matches /{expect['depth_errors']}/: {errors}")
        elif kind == "drops":
            for key, count in expect["drops"].items():
                if doc["drops"].get(key, 0) != count:
                    fail(cid, f"expected drops[{key}] = {count}, got {doc['drops']}")
            if "samples_min" in expect and doc["samples"] < expect["samples_min"]:
                fail(cid, f"expected at least {expect['samples_min']} samples, got {doc['samples']}")
            for key, pattern in expect.get("drop_examples", {}).items():
                if not re.search(pattern, doc.get("drop_examples", {}).get(key, "")):
                    fail(cid, f"drop_examples[{key}] does not match /{pattern}/: "
                              f"{doc.get('drop_examples')}")
    elif kind == "problem":
        if r.returncode != 1:
            fail(cid, f"expected exit 1{shown}\n  stdout: {r.stdout}")
            return
        if len(lines) != 1 or not re.search(r"^occgt: error: .*problem\(s\) found", lines[0]):
            fail(cid, f"expected one 'N problem(s) found' line on stderr{shown}")
        if not any(re.search(expect["stdout"], l) for l in r.stdout.splitlines()):
            fail(cid, f"no stdout line matches /{expect['stdout']}/{shown}\n  stdout: {r.stdout}")
    else:
        fail(cid, f"unknown expect.kind {kind}")
        return
    for rel in expect.get("absent", []):
        if os.path.lexists(os.path.join(case_dir, rel)):
            fail(cid, f"{rel} exists after the failure")
    leftovers = tmp_files(case_dir)
    if leftovers:
        fail(cid, f"*.tmp left behind: {leftovers}")
    default_outputs = {"fatal": "none"}.get(kind, "any")
    check_outputs(cid, subst["out"], expect.get("outputs", default_outputs))


def check_bases(cache):
    """Each base is valid: every reader sees it without unusable frames; validate passes."""
    for base, fmt in [("scannet", "scannet"), ("tartanair", "tartanair"),
                      ("sevenscenes", "sevenscenes"), ("tum", "tum"), ("generic", "generic")]:
        d = common.scratch(f"badinput/_base_{base}")
        generators.build_case(d, {"id": base, "base": base}, common.occgt, cache)
        r, _ = run(["scan", os.path.join(d, "data"), "--format", fmt, "--json", "--check-depth"])
        if r.returncode != 0:
            fail(f"base {base}", f"scan failed: {r.stderr}")
            continue
        totals = json.loads(r.stdout)["totals"]
        if totals["unusable"] != 0 or totals["frames"] < 4:
            fail(f"base {base}", f"expected >= 4 usable frames, got {totals}")
    d = common.scratch("badinput/_base_build")
    generators.build_case(d, {"id": "build", "base": "build"}, common.occgt, cache)
    r, _ = run(["validate", os.path.join(d, "out")])
    if r.returncode != 0:
        fail("base build", f"validate failed on the unmodified build: {r.stdout}{r.stderr}")
    with open(os.path.join(d, "out", "index.json")) as f:
        if len(json.load(f)["shardlist"]) < 3:
            fail("base build", "expected at least 3 shards in the base build")
    # The covisibility graph gives tuples, the pair folder draws (so their cases test occgt).
    d = common.scratch("badinput/_base_covis")
    generators.build_case(d, {"id": "covis", "base": "covis"}, common.occgt, cache)
    r, _ = run(["tuples", "--json", os.path.join(d, "recipe.yaml"), "--out", os.path.join(d, "out")])
    if r.returncode != 0 or json.loads(r.stdout)["tuples"] < 1:
        fail("base covis", f"occgt tuples gives no tuple on the unmodified graph: {r.stdout}{r.stderr}")
    d = common.scratch("badinput/_base_tuples")
    generators.build_case(d, {"id": "tuples", "base": "tuples"}, common.occgt, cache)
    r, _ = run(["validate", os.path.join(d, "out", "views")])
    if r.returncode != 0:
        fail("base tuples", f"validate failed on the unmodified N-view split: {r.stdout}{r.stderr}")
    d = common.scratch("badinput/_base_pair")
    generators.build_case(d, {"id": "pair", "base": "pair"}, common.occgt, cache)
    r, _ = run(["inspect", "pair", "--pair-dir", os.path.join(d, "pair"), "--out",
                os.path.join(d, "pictures")])
    if r.returncode != 0 or "matches" not in r.stdout or "occupancy" not in r.stdout:
        fail("base pair", f"inspect pair does not draw the unmodified folder: {r.stdout}{r.stderr}")
    # The hand-written EXR of generators.exr_bytes reads back (so the EXR cases test occgt).
    d = common.scratch("badinput/_base_exr")
    generators.build_case(d, {"id": "exr", "base": "generic", "mutate": EXR_FRAME0}, common.occgt,
                          cache)
    r, _ = run(["scan", os.path.join(d, "data"), "--format", "generic", "--json", "--check-depth"])
    if r.returncode != 0 or json.loads(r.stdout)["totals"]["unusable"] != 0:
        fail("base exr", f"a valid hand-made EXR is not read: {r.stdout}{r.stderr}")


EXR_FRAME0 = [
    {"op": "exr", "path": "data/synth_000/depth/000000.exr", "width": 64, "height": 48,
     "channels": ["View Layer.Depth.Z"]},
    {"op": "json_set", "path": "data/synth_000/scene.json", "pointer": "/frames/0/depth",
     "value": {"path": "depth/000000.exr", "format": "exr"}},
]


def check_readme(cases):
    with open(os.path.join(CORPUS, "README.md")) as f:
        text = f.read()
    listed = set(re.findall(r"^\| `([a-z0-9-]+)` \|", text, re.M))
    ids = [c["id"] for c in cases]
    for cid in ids:
        if cid not in listed:
            fail("README", f"case {cid} is not listed in tests/badinput/README.md")
    for cid in sorted(listed - set(ids)):
        fail("README", f"README lists {cid}, which is not in cases.json")


ESCAPES = [
    # (base, reader format, scene folder under data/, hostile new name)
    ("generic", "generic", "synth_000", "a\x07b..c"),
    ("scannet", "scannet", "scene0000_00", "scene\x1b[31m..x y"),
    ("tum", "tum", "rgbd_dataset_freiburg1_xyz", "fr1\t..\u00e9"),
]


def check_escape(cache, base, fmt, folder, hostile):
    """A hostile scene folder name builds with sanitised member and file names, all
    inside --out, also when --out is a symlink."""
    tag = f"escape/{base}"
    root = common.scratch(f"badinput/_escape_{base}")
    generators.BASES[base](root, common.occgt, cache)
    data = os.path.join(root, "data")
    os.rename(os.path.join(data, folder), os.path.join(data, hostile))
    generators.write_text(os.path.join(root, "recipe.yaml"),
                          generators.RECIPE.replace("format: generic", f"format: {fmt}"))
    if base == "scannet":
        shutil.rmtree(os.path.join(root, "outside"))
    real_out = os.path.join(root, "real_out")
    os.makedirs(real_out)
    os.symlink(real_out, os.path.join(root, "out"))
    before = set(os.listdir(root))
    r, _ = run(["build", "--json", os.path.join(root, "recipe.yaml"), "--out", os.path.join(root, "out")])
    if r.returncode != 0:
        fail(tag, f"build over a hostile scene name failed: {r.stderr}")
        return
    if set(os.listdir(root)) != before:
        fail(tag, f"build wrote next to --out: {set(os.listdir(root)) ^ before}")
    if not os.path.islink(os.path.join(root, "out")):
        fail(tag, "--out symlink was replaced")
    tars = [n for n in os.listdir(real_out) if n.endswith(".tar")]
    if not tars:
        fail(tag, "no shard written")
    for t in tars:
        with tarfile.open(os.path.join(real_out, t)) as tar:
            for m in tar.getmembers():
                n = m.name
                if (n.startswith("/") or ".." in n.split("/") or
                        any(ord(c) < 0x21 or ord(c) >= 0x7f for c in n) or "." in n.split("/")[0]):
                    fail(tag, f"{t}: unsafe member name {n!r}")
    for dirpath, dirnames, filenames in os.walk(real_out):
        for n in dirnames + filenames:
            if any(ord(c) < 0x20 for c in n) or n in ("..", "."):
                fail(tag, f"unsafe output file name {os.path.join(dirpath, n)!r}")
    r, _ = run(["validate", os.path.join(root, "out")])
    if r.returncode != 0:
        fail(tag, f"validate of the symlinked --out failed: {r.stdout}{r.stderr}")


def expected_text(e):
    kind = e["kind"]
    if kind == "fatal":
        extra = {"complete": "; only complete shards stay", "any": ""}.get(e.get("outputs"), "; nothing published")
        fast = f"; fails within {e['max_seconds']} s" if "max_seconds" in e else ""
        return f"exit {e.get('exit', 1)}, one stderr line /{e['line']}/{extra}{fast}"
    if kind == "skipped":
        reasons = ", ".join(f"{n} x /{r}/" for r, n in e["reasons"].items())
        details = "".join(f", detail /{d}/" for d in e.get("details", []))
        return f"exit 0; scan --json counts {reasons}{details}"
    if kind == "drops":
        return "exit 0; build summary drops " + ", ".join(f"{k} = {n}" for k, n in e["drops"].items())
    if kind == "problem":
        return f"validate exit 1; a stdout line /{e['stdout']}/"
    return "exit 0"


def readme_table(cases):
    """The case table of tests/badinput/README.md (print with --readme-table)."""
    rows = ["| case | area | what is broken | expected |", "|---|---|---|---|"]
    for c in cases:
        cell = expected_text(c["expect"]).replace("|", "\\|")
        rows.append(f"| `{c['id']}` | {c['area']} | {c['broken'].replace('|', '/')} | {cell} |")
    return "\n".join(rows) + "\n"


def main():
    if "--readme-table" in sys.argv:
        with open(os.path.join(CORPUS, "cases.json")) as f:
            sys.stdout.write(readme_table(json.load(f)["cases"]))
        return
    if not common.BINARY or not os.path.exists(common.BINARY):
        sys.exit(f"FAIL: occgt binary missing: {common.BINARY!r}")
    with open(os.path.join(CORPUS, "cases.json")) as f:
        corpus = json.load(f)
    cases = corpus["cases"]
    ids = [c["id"] for c in cases]
    if len(ids) != len(set(ids)):
        sys.exit("FAIL: duplicate case ids in cases.json")
    only = os.environ.get("BADINPUT_ONLY")
    cache = common.scratch("badinput/_cache")
    check_readme(cases)
    if not only:
        check_bases(cache)
    for spec in cases:
        if only and not re.search(only, spec["id"]):
            continue
        if spec.get("skip"):
            print(f"SKIP {spec['id']}: {spec['skip']}")
            continue
        case_dir = common.scratch(f"badinput/{spec['id']}")
        try:
            generators.build_case(case_dir, spec, common.occgt, cache)
        except Exception as e:  # a broken generator is a broken test
            fail(spec["id"], f"generator failed: {type(e).__name__}: {e}")
            continue
        check_case(spec, case_dir)
    if not only:
        for escape in ESCAPES:
            check_escape(cache, *escape)
    areas = {}
    for c in cases:
        areas[c["area"]] = areas.get(c["area"], 0) + 1
    print(f"{len(cases)} cases: " + ", ".join(f"{a} {n}" for a, n in sorted(areas.items())))
    if FAILURES:
        sys.exit(f"FAIL: {len(FAILURES)} problem(s):\n" + "\n".join(FAILURES))
    print("OK")


if __name__ == "__main__":
    main()
