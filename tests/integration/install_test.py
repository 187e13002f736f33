"""`cmake --install` puts a working occgt under PREFIX/bin with the shipped recipes and
schemas under PREFIX/share/occgt (docs/USER_GUIDE.md, "Install"), and scripts/occgt builds
only the binary (scripts/test builds the rest).

The installed binary is run from an unrelated folder on an installed recipe: it must not
depend on the source or build tree.
"""
import os
import subprocess
import sys

sys.path.insert(0, os.path.dirname(__file__))
import common  # noqa: E402


def main():
    build_dir = os.path.dirname(os.path.dirname(os.path.abspath(common.BINARY)))
    prefix = common.scratch("install_prefix")
    r = subprocess.run(["cmake", "--install", build_dir, "--prefix", prefix],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr + r.stdout
    exe = os.path.join(prefix, "bin", "occgt")
    assert os.access(exe, os.X_OK), f"no executable {exe}: {r.stdout}"
    share = os.path.join(prefix, "share", "occgt")
    for rel in ("recipes/demo.yaml", "schemas/recipe.schema.json", "schemas/summary.schema.json"):
        assert os.path.isfile(os.path.join(share, rel)), f"missing {rel} under {share}"
    # Only what was asked for: no tests, benchmarks or static libraries installed.
    installed = sorted(os.path.relpath(os.path.join(d, f), prefix)
                       for d, _, fs in os.walk(prefix) for f in fs)
    stray = [p for p in installed if not (p == "bin/occgt" or p.startswith("share/occgt/"))]
    assert not stray, f"unexpected installed files: {stray}"

    work = common.scratch("install_run")
    env = dict(os.environ, PATH=os.path.join(prefix, "bin") + os.pathsep + os.environ.get("PATH", ""))
    out = os.path.join(work, "demo")
    r = subprocess.run(["occgt", "build", os.path.join(share, "recipes", "demo.yaml"), "--out", out, "--json"],
                       cwd=work, env=env, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert os.path.isfile(os.path.join(out, "summary.json")), os.listdir(out)
    assert os.path.isfile(os.path.join(out, "index.json")), os.listdir(out)

    # scripts/occgt asks setup.sh for the occgt target only.
    launcher = open(os.path.join(common.SOURCE, "scripts", "occgt"), encoding="utf-8").read()
    assert "setup.sh\" --target occgt" in launcher, launcher
    print("install: ok", len(installed), "files")


if __name__ == "__main__":
    main()
