"""Shared helpers of the tests of the Python package occgt (tests/python/CMakeLists.txt sets
the environment: PYTHONPATH = build/python, the occgt binary, ../shared/data, a scratch
folder). Run with Debian's /usr/bin/python3."""
from __future__ import annotations

import gzip
import io
import json
import os
import shutil
import subprocess
import sys
import tarfile
from typing import Any, Dict, List, Mapping, Optional, Sequence

import cv2
import numpy as np

BINARY: str = os.environ.get("OCCGT_BINARY", "")
SHARED: str = os.environ.get("OCCGT_SHARED_DATA", "")
SOURCE: str = os.environ.get("OCCGT_SOURCE_DIR", "")
BUILD: str = os.environ.get("OCCGT_BUILD_DIR", "")
SCRATCH: str = os.environ.get("OCCGT_SCRATCH", "/tmp/occgt-python-scratch")

#: Every array file of an `occgt pair` folder (libgt/truth/pair_files.h).
PAIR_ARRAYS: List[str] = ["label01", "label10", "matches", "match_type", "match_xy", "cells0",
                          "cells1"]
OCCUPANCY_ARRAYS: List[str] = ["occ0", "known0", "occ1", "known1"]
PRESETS: List[str] = ["default", "occ2net", "occ2net-compat", "loftr", "superglue", "megadepth"]


def shared(rel: str) -> str:
    """Path under ../shared/data; fails loudly (exit 1) when the real samples are missing."""
    p = os.path.join(SHARED, rel)
    if not SHARED or not os.path.exists(p):
        sys.exit(f"FAIL: real sample data missing: {p!r} (OCCGT_SHARED_DATA={SHARED!r})")
    return p


def scratch(name: str) -> str:
    """A fresh, empty folder under the build tree."""
    p = os.path.join(SCRATCH, name)
    shutil.rmtree(p, ignore_errors=True)
    os.makedirs(p)
    return p


def occgt(*args: Any) -> subprocess.CompletedProcess:
    """Runs the occgt binary; raises AssertionError with its stderr when it fails."""
    if not BINARY or not os.path.exists(BINARY):
        raise AssertionError(f"occgt binary missing: {BINARY!r} (OCCGT_BINARY)")
    r = subprocess.run([BINARY, *map(str, args)], capture_output=True, text=True)
    if r.returncode != 0:
        raise AssertionError(f"occgt {' '.join(map(str, args))} failed ({r.returncode}):\n{r.stderr}")
    return r


def synth_dataset(name: str, frames: int = 4, resolution: str = "320x240", seed: int = 7) -> str:
    """A synthetic dataset of one room written by `occgt synth` (docs/SYNTH.md), generic
    format; returns its root."""
    out = scratch(name)
    occgt("synth", "--out", out, "--scenes", 1, "--frames", frames, "--resolution", resolution,
          "--seed", seed)
    return out


def npy_bytes(a: np.ndarray) -> bytes:
    """The bytes numpy.save writes for a."""
    buf = io.BytesIO()
    np.save(buf, a)
    return buf.getvalue()


def read_bytes(path: str) -> bytes:
    with open(path, "rb") as f:
        return f.read()


def read_json(path: str) -> Dict[str, Any]:
    with open(path) as f:
        return json.load(f)


def assert_same_as_folder(test: Any, result: Mapping[str, Any], folder: str,
                          names: Sequence[str], where: str) -> None:
    """Every array of result saved with numpy.save is byte-identical to folder/<name>.npy."""
    for name in names:
        ref = read_bytes(os.path.join(folder, name + ".npy"))
        got = npy_bytes(result[name])
        if got != ref:
            back = np.load(os.path.join(folder, name + ".npy"))
            detail = (f"dtype {result[name].dtype} vs {back.dtype}, shape {result[name].shape} "
                      f"vs {back.shape}")
            if result[name].shape == back.shape:
                detail += f", {int(np.sum(result[name] != back))} values differ"
            test.fail(f"{where}: {name} differs from {folder}/{name}.npy ({detail})")


def assert_same_as_pair_folder(test: Any, result: Mapping[str, Any], folder: str,
                               where: str) -> Dict[str, Any]:
    """result of pair_ground_truth == the `occgt pair` folder: every .npy byte for byte, the
    metrics of meta.json and its cam1_from_cam0. Returns meta.json."""
    assert_same_as_folder(test, result, folder, PAIR_ARRAYS, where)
    meta = read_json(os.path.join(folder, "meta.json"))
    test.assertEqual(result["metrics01"], meta["metrics"]["01"], where)
    test.assertEqual(result["metrics10"], meta["metrics"]["10"], where)
    test.assertEqual(result["T_0to1"].tolist(), meta["T_0to1"], where)
    return meta


def pair_cli(root: str, fmt: str, scene: str, frames: str, out: str,
             extra: Optional[Sequence[Any]] = None) -> None:
    occgt("pair", "--root", root, "--format", fmt, "--scene", scene, "--frames", frames, "--out",
          out, *(extra or []))


def read_shard_samples(folder: str, images: bool = True) -> List[Dict[str, Any]]:
    """Every sample of the shards listed in folder/index.json, in order, its members decoded:
    ".gz" inflated, ".npy" loaded, ".json" parsed under "json", images (when `images`)
    decoded to RGB under their name without extension, other members skipped."""
    with open(os.path.join(folder, "index.json")) as f:
        index = json.load(f)
    samples: List[Dict[str, Any]] = []
    for shard in index["shardlist"]:
        current: Dict[str, Any] = {}
        with tarfile.open(os.path.join(folder, shard["url"])) as tar:
            for m in tar.getmembers():
                key, field = m.name.split(".", 1)
                data = tar.extractfile(m).read()  # type: ignore[union-attr]
                if field.endswith(".gz"):
                    field, data = field[:-3], gzip.decompress(data)
                if current.get("__key__") != key:
                    current = {"__key__": key}
                    samples.append(current)
                if field.endswith(".npy"):
                    current[field[:-4]] = np.load(io.BytesIO(data))
                elif field == "json":
                    current["json"] = json.loads(data)
                elif images:
                    bgr = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_COLOR)
                    current[field.split(".")[0]] = cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)
    return samples
