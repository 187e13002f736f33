"""Ground truth does not depend on the floating-point mode of the calling threads.

torch.set_flush_denormal(True) (a trainer's CPU speed-up) sets flush-to-zero and
denormals-are-zero; Embree's BVH build (occgt.load_mesh) used to leave the same mode in the
caller's TBB arena. Under it a comparison with a denormal threshold had counted depth 0 as
valid: every hole pixel became OUT_OF_VIEW instead of NO_DEPTH (docs/GROUND_TRUTH.md).
Here every preset's pair ground truth and the N-view ground truth are computed with and
without the mode, on depth with holes (0), denormal and NaN values, and must be equal
byte for byte, with NO_DEPTH at every such pixel; a fresh process that loads a mesh first
gets the same labels as one that does not."""
from __future__ import annotations

import hashlib
import os
import subprocess
import sys
import unittest
from typing import Any, Dict

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
import common  # noqa: E402

import occgt  # noqa: E402

H, W = 48, 64
K = np.array([[60.0, 0, 31.5], [0, 60.0, 23.5], [0, 0, 1]])


def depth_with_holes(seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    d = (2.0 + 0.5 * rng.random((H, W))).astype(np.float32)
    d[:6] = 0.0                      # a hole
    d[10, 5:20] = np.float32(1e-40)  # denormal depths: invalid
    d[20, :8] = np.nan
    return d


def pose(tx: float, yaw: float) -> np.ndarray:
    c, s = np.cos(yaw), np.sin(yaw)
    t = np.eye(4)
    t[:3, :3] = [[c, 0, s], [0, 1, 0], [-s, 0, c]]
    t[0, 3] = tx
    return t


DEPTHS = [depth_with_holes(s) for s in range(3)]
POSES = [pose(0.0, 0.0), pose(0.15, 0.05), pose(-0.1, -0.08)]
INVALID = [~(np.isfinite(d) & (d >= np.finfo(np.float32).tiny)) for d in DEPTHS]


def compute() -> Dict[str, Any]:
    out: Dict[str, Any] = {}
    for preset in common.PRESETS:
        r = occgt.pair_ground_truth(DEPTHS[0], DEPTHS[1], K, K, POSES[0], POSES[1], preset=preset)
        for key, value in r.items():
            out[f"pair/{preset}/{key}"] = value
    v = occgt.views_ground_truth(DEPTHS, [K] * 3, POSES, num_tracks=64, seed=3)
    for key, value in v.items():
        out[f"views/{key}"] = value
    return out


def digest(results: Dict[str, Any]) -> str:
    h = hashlib.sha256()
    for key in sorted(results):
        value = results[key]
        h.update(key.encode())
        if isinstance(value, np.ndarray):
            h.update(str(value.dtype).encode() + str(value.shape).encode() + value.tobytes())
        else:
            h.update(repr(value).encode())
    return h.hexdigest()


# Each mode in a fresh process, set before any TBB work: "flush" sets flush-to-zero and
# denormals-are-zero on the main thread (torch.set_flush_denormal), "mesh" loads a mesh
# (Embree's BVH build) first, "none" neither.
SCRIPT = """
import sys
sys.path.insert(0, {here!r})
import torch
import fp_mode_test as t
import occgt
if sys.argv[1] == "flush":
    assert torch.set_flush_denormal(True)
if sys.argv[1] == "mesh":
    occgt.load_mesh({mesh!r})
sys.stdout.write(t.digest(t.compute()))
"""


class FloatingPointMode(unittest.TestCase):
    def test_labels(self) -> None:
        results = compute()
        for preset in common.PRESETS:
            for key, invalid in (("label01", INVALID[0]), ("label10", INVALID[1])):
                label = results[f"pair/{preset}/{key}"]
                self.assertTrue((label[invalid] == occgt.NO_DEPTH).all(), (preset, key))
                self.assertTrue((label[~invalid] != occgt.NO_DEPTH).all(), (preset, key))
        for i, invalid in enumerate(INVALID):
            self.assertEqual(results["views/valid"][i].astype(bool).tolist(), (~invalid).tolist())

    def test_same_results_in_every_mode(self) -> None:
        mesh = common.shared("meshes/sevenscenes-rgbd-frames-tsdf.ply")
        script = SCRIPT.format(here=os.path.dirname(os.path.abspath(__file__)), mesh=mesh)
        digests = {}
        for mode in ("none", "flush", "mesh"):
            r = subprocess.run([sys.executable, "-c", script, mode], capture_output=True,
                               text=True, check=False)
            self.assertEqual(r.returncode, 0, r.stderr)
            digests[mode] = r.stdout
        self.assertEqual(digests["none"], digest(compute()))
        self.assertEqual(digests["flush"], digests["none"])
        self.assertEqual(digests["mesh"], digests["none"])


if __name__ == "__main__":
    unittest.main()
