"""occgt synth, read as a trainer would: every scene.json validates against
schemas/manifest.schema.json (jsonschema, draft 2020-12), depth files load with NumPy as
float32 (H, W) with zeros exactly in the holes recorded in dataset.json, colour PNGs have
the stated size, poses are rigid, reruns are byte-identical, and occgt's own generic reader
(occgt scan --format generic --check-depth) reads the result."""
import hashlib
import json
import os
import sys
import struct

import jsonschema
import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
import common  # noqa: E402


def png_size(path):
    with open(path, "rb") as f:
        head = f.read(33)
    assert head[:8] == b"\x89PNG\r\n\x1a\n", path
    width, height, depth, colour = struct.unpack(">IIBB", head[16:26])
    return width, height, depth, colour


def tree_digest(root):
    out = {}
    for d, _, files in os.walk(root):
        for name in files:
            p = os.path.join(d, name)
            with open(p, "rb") as f:
                out[os.path.relpath(p, root)] = hashlib.md5(f.read()).hexdigest()
    return out


def main():
    schema_path = os.path.join(common.SOURCE, "schemas", "manifest.schema.json")
    with open(schema_path) as f:
        schema = json.load(f)
    validator = jsonschema.Draft202012Validator(schema)

    out = common.scratch("synth_a")
    r = common.occgt("synth", "--out", out, "--scenes", 2, "--frames", 5,
                     "--resolution", "160x120", "--seed", 3)
    assert "2 scenes, 10 frames" in r.stdout, r.stdout

    with open(os.path.join(out, "dataset.json")) as f:
        dataset = json.load(f)
    assert [s["name"] for s in dataset["scenes"]] == ["synth_000", "synth_001"]
    hole_pixels = 0
    for entry in dataset["scenes"]:
        manifest_path = os.path.join(out, entry["manifest"])
        with open(manifest_path) as f:
            manifest = json.load(f)
        errors = sorted(validator.iter_errors(manifest), key=lambda e: e.path)
        assert not errors, [f"{list(e.path)}: {e.message}" for e in errors]
        assert manifest["scene"] == entry["name"]
        assert len(manifest["frames"]) == 5
        base = os.path.dirname(manifest_path)
        for frame in manifest["frames"]:
            K = np.array(frame["K"])
            assert K[0, 0] == K[1, 1] == 525.0 * 160 / 640
            assert (K[0, 2], K[1, 2]) == (79.5, 59.5)
            T = np.array(frame["world_from_cam"])
            R = T[:3, :3]
            assert np.abs(R.T @ R - np.eye(3)).max() < 1e-12
            assert abs(np.linalg.det(R) - 1) < 1e-12
            assert (T[3] == [0, 0, 0, 1]).all()
            depth = np.load(os.path.join(base, frame["depth"]["path"]))
            assert depth.dtype == np.float32 and depth.shape == (120, 160), (depth.dtype, depth.shape)
            hole = np.zeros_like(depth, dtype=bool)
            for x0, y0, x1, y1 in entry["holes"][frame["id"]]:
                hole[y0:y1, x0:x1] = True
            assert (depth[hole] == 0).all()
            assert (depth[~hole] > 0.3).all() and (depth[~hole] < 20).all()
            hole_pixels += int(hole.sum())
            w, h, bits, colour = png_size(os.path.join(base, frame["color"]["path"]))
            assert (w, h, bits, colour) == (160, 120, 8, 2), (w, h, bits, colour)  # 8-bit RGB
    assert hole_pixels > 0

    # A rerun gives identical bytes; another seed does not.
    again = common.scratch("synth_b")
    common.occgt("synth", "--out", again, "--scenes", 2, "--frames", 5,
                 "--resolution", "160x120", "--seed", 3)
    assert tree_digest(out) == tree_digest(again)
    other = common.scratch("synth_c")
    common.occgt("synth", "--out", other, "--scenes", 2, "--frames", 5,
                 "--resolution", "160x120", "--seed", 4)
    assert tree_digest(out) != tree_digest(other)

    # occgt's generic reader reads it (frames, K and every depth file).
    scan = common.occgt("scan", out, "--format", "generic", "--json", "--check-depth")
    report = json.loads(scan.stdout)
    assert [s["name"] for s in report["scenes"]] == ["synth_000", "synth_001"]
    for s in report["scenes"]:
        assert s["frames"] == 5 and s["usable"] == 5
        assert s["depth_check"]["files_bad"] == 0
        assert 0.8 < s["depth_check"]["mean_valid_fraction"] < 1.0

    # A run that did not finish (killed before dataset.json, which is written last) is not
    # read as a smaller dataset: every reader entry refuses the folder, naming dataset.json,
    # for the generic and the ScanNet++ layouts (a scene folder as root too); a re-run of the
    # same command completes it.
    cut = common.scratch("synth_cut")
    common.occgt("synth", "--out", cut, "--scenes", 2, "--frames", 3, "--resolution", "160x120")
    pp = common.scratch("synth_cut_pp")
    common.occgt("synth", "--out", pp, "--layout", "scannetpp", "--scenes", 1, "--frames", 4)
    with open(os.path.join(pp, "dataset.json")) as f:
        assert json.load(f)["scenes"] == ["synthpp_000"]
    for folder in (cut, pp):
        os.remove(os.path.join(folder, "dataset.json"))
    want = "dataset.json: missing: the folder is an `occgt synth` dataset whose run did not finish"
    for argv in (["scan", cut, "--format", "generic"],
                 ["scan", os.path.join(cut, "synth_001"), "--format", "generic"],
                 ["pair", "--root", cut, "--format", "generic", "--scene", "synth_000",
                  "--frames", "000000,000001", "--out", common.scratch("synth_cut_pair")],
                 ["scan", pp, "--format", "scannetpp"],
                 ["scan", os.path.join(pp, "data"), "--format", "scannetpp"],
                 ["scan", os.path.join(pp, "data", "synthpp_000"), "--format", "scannetpp"]):
        r = common.occgt(*argv, check=False)
        assert r.returncode == 1 and want in r.stderr, (argv, r.returncode, r.stderr)
    common.occgt("synth", "--out", cut, "--scenes", 2, "--frames", 3, "--resolution", "160x120")
    assert "2 scene(s)" in common.occgt("scan", cut, "--format", "generic").stdout

    # Usage errors (docs/CLI.md): one `occgt: error: --flag` line on stderr, exit 2.
    bad = common.occgt("synth", "--out", out, "--resolution", "160", check=False)
    assert bad.returncode == 2 and bad.stderr.startswith("occgt: error: --resolution: "), bad.stderr
    assert bad.stderr.count("\n") == 1, bad.stderr
    cli_example()
    printed_commands_run()
    print("ok")


def cli_example():
    """docs/CLI.md's synth example, run as written in an empty folder: every line it shows,
    the time of the first line excepted."""
    import re
    import subprocess
    cli = open(os.path.join(common.SOURCE, "docs", "CLI.md"), encoding="utf-8").read()
    m = re.search(r"^## synth\n.*?^Example [^\n]*\n[^\n]*\n\n((?:    [^\n]*\n)+)", cli, re.S | re.M)
    assert m, "docs/CLI.md: synth example not found"
    lines = [ln[4:] for ln in m.group(1).splitlines()]
    cwd = common.scratch("synth_cli_example")
    commands = [i for i, ln in enumerate(lines) if ln.startswith("$ occgt ")]
    assert len(commands) == 2, lines
    for k, i in enumerate(commands):
        end = commands[k + 1] if k + 1 < len(commands) else len(lines)
        argv = lines[i][2:].split()[1:]
        r = subprocess.run([common.BINARY, *argv], cwd=cwd, capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
        got, want = r.stdout.splitlines(), lines[i + 1:end]
        if k == 0:
            time = re.compile(r" in [0-9]+\.[0-9]{2} s$")
            assert time.search(got[0]) and time.search(want[0]), (got[0], want[0])
            got[0], want[0] = time.sub("", got[0]), time.sub("", want[0])
        assert got == want, (got, want)


def printed_commands_run():
    """The commands synth and build print to look at their output (`read it with --format
    generic DIR`, `see it with: occgt inspect split DIR`) run as printed through a shell, for
    an output folder whose name starts with '-' and holds a space, a quote and non-ASCII (they
    printed the name as is: the shell split it, or occgt read it as a flag)."""
    import shlex
    import subprocess
    cwd = common.scratch("synth_printed_commands")
    name = "-a b'c \u00e9"

    def printed(stdout, prefix):
        line = next(ln for ln in stdout.splitlines() if prefix in ln)
        return line.split(prefix, 1)[1]

    def run_printed(command):
        r = subprocess.run(["sh", "-c", command], cwd=cwd, capture_output=True, text=True,
                           env=dict(os.environ, PATH=os.path.dirname(common.BINARY) + os.pathsep +
                                    os.environ.get("PATH", "")))
        assert r.returncode == 0, (command, r.stderr)
        return r.stdout

    r = subprocess.run([common.BINARY, "synth", "--out", name, "--scenes", "1", "--frames", "2",
                        "--resolution", "16x16"], cwd=cwd, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    word = printed(r.stdout, "read it with --format generic ")
    assert shlex.split(word) == ["./" + name], word
    assert "total: 1 scene(s)" in run_printed("occgt scan " + word + " --format generic")
    with open(os.path.join(cwd, "recipe.yaml"), "w") as f:
        f.write("name: printed\nresolution: [16, 16]\n"
                "dataset: {format: synthetic, synthetic: {scenes: 1, frames: 2, width: 16, "
                "height: 16, seed: 0}, min_valid_depth_fraction: 0}\n"
                "selection: {pruning: {frustum: false}}\noccupancy: {enabled: false}\n")
    out = name + "-split"
    r = subprocess.run([common.BINARY, "build", "recipe.yaml", "--out", out], cwd=cwd,
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    command = "occgt " + printed(r.stdout, "see it with: occgt ")
    assert shlex.split(command)[-1] == "./" + out, command
    assert "report.html" in run_printed(command)


if __name__ == "__main__":
    main()
