"""Shared helpers for the Python integration tests (run with Debian's /usr/bin/python3)."""
import os
import shutil
import subprocess
import sys

BINARY = os.environ.get("OCCGT_BINARY", "")
SHARED = os.environ.get("OCCGT_SHARED_DATA", "")
SOURCE = os.environ.get("OCCGT_SOURCE_DIR", "")
SCRATCH = os.environ.get("OCCGT_SCRATCH", "/tmp/occgt-scratch")


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
