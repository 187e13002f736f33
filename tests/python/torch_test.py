"""occgt inside a PyTorch input pipeline, as a trainer uses it: a torch Dataset computing each
pair's ground truth, read through DataLoader with 0 and 2 worker processes (forked after the
parent already ran the TBB-parallel C++ code), tensors shared with the NumPy outputs
(torch.from_numpy, no copy), torch tensors accepted as inputs. python3-torch comes with
`scripts/setup.sh --test`; without it the test is skipped."""
from __future__ import annotations

import os
import sys
import unittest
from typing import Any, Dict, List

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
import common  # noqa: E402

import occgt  # noqa: E402

try:
    import torch
    from torch.utils.data import DataLoader, Dataset
except ImportError:  # pragma: no cover - reported as a skip
    torch = None  # type: ignore[assignment]
    Dataset = object  # type: ignore[assignment,misc]


class PairDataset(Dataset):  # type: ignore[misc,valid-type]
    """Pairs (i, i + gap) of one scene; each item the ground truth as tensors."""

    def __init__(self, scene: occgt.Scene, count: int, gap: int) -> None:
        self.scene = scene
        self.ids = [f.id for f in scene.frames if f.usable]
        self.count, self.gap = count, gap

    def __len__(self) -> int:
        return self.count

    def __getitem__(self, i: int) -> Dict[str, Any]:
        gt = occgt.pair_from_scene(self.scene, self.ids[i], self.ids[i + self.gap],
                                   occupancy=True, voxel_m=0.1)
        return {
            "label01": torch.from_numpy(gt["label01"]),
            "cells0": torch.from_numpy(gt["cells0"]),
            "T_0to1": torch.from_numpy(gt["T_0to1"]),
            # torch has no uint64: the words reinterpreted as int64 (same bits).
            "occ0": torch.from_numpy(gt["occ0"].view(np.int64)),
            "overlap": gt["metrics01"]["overlap"],
        }


@unittest.skipIf(torch is None, "python3-torch is not installed (scripts/setup.sh --test)")
class Torch(unittest.TestCase):
    @classmethod
    def setUpClass(cls) -> None:
        root = common.shared("sevenscenes")
        cls.scene = occgt.open_dataset(root, "sevenscenes").scene("rgbd-frames")

    def test_from_numpy_shares_memory(self) -> None:
        d0, K0, T0 = self.scene.load("000150")
        d1, K1, T1 = self.scene.load("000160")
        gt = occgt.pair_ground_truth(d0, d1, K0, K1, T0, T1)
        t = torch.from_numpy(gt["label01"])
        self.assertEqual(t.data_ptr(), gt["label01"].ctypes.data)
        # Tensors as inputs (through numpy.asarray): the same result.
        gt2 = occgt.pair_ground_truth(torch.from_numpy(d0), torch.from_numpy(d1).double(),
                                      torch.from_numpy(K0), K1, torch.from_numpy(T0), T1)
        for key in common.PAIR_ARRAYS:
            self.assertTrue(np.array_equal(gt[key], gt2[key]), key)

    def test_dataloader_workers(self) -> None:
        data = PairDataset(self.scene, count=6, gap=5)
        reference: List[Dict[str, Any]] = [data[i] for i in range(len(data))]
        for workers in (0, 2):
            with self.subTest(num_workers=workers):
                loader = DataLoader(data, batch_size=2, num_workers=workers)
                batches = list(loader)
                self.assertEqual(len(batches), 3)
                self.assertEqual(tuple(batches[0]["label01"].shape), (2, 480, 640))
                self.assertEqual(tuple(batches[0]["occ0"].shape), (2, 240, 320))
                for k, ref in enumerate(reference):
                    b = batches[k // 2]
                    for key in ["label01", "cells0", "T_0to1", "occ0"]:
                        self.assertTrue(torch.equal(b[key][k % 2], ref[key]), (workers, k, key))
                    self.assertEqual(float(b["overlap"][k % 2]), ref["overlap"])


if __name__ == "__main__":
    unittest.main(verbosity=2)
