"""TUM's association tolerance from Python (docs/PYTHON.md): open_dataset(tum_max_dt_s=...),
PairIndexDataset(tum_max_dt_s=...) and PairIndexDataset.from_split of a build whose recipe
gives dataset.tum_max_dt_s read the frames the build read (tests/integration/
tum_tolerance_test.py does the same for the CLI)."""
from __future__ import annotations

import json
import os
import sys
import unittest

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "support"))
import common  # noqa: E402
from tum_sequence import make_sequence  # noqa: E402

import occgt  # noqa: E402
from occgt.torch import PairIndexDataset  # noqa: E402


class TumTolerance(unittest.TestCase):
    def test_open_dataset_and_datasets(self) -> None:
        root = common.scratch("py_tum_tolerance")
        seq = make_sequence(root)
        self.assertEqual(occgt.DATASET_DEFAULTS["tum_max_dt_s"], 0.02)
        for dt, usable in ((None, 4), (0.02, 4), (0.05, 8)):
            scene = occgt.open_dataset(seq, "tum", tum_max_dt_s=dt).scene("")
            self.assertEqual(sum(f.usable for f in scene.frames), usable, dt)
        for bad in (-1.0, float("nan"), float("inf")):
            with self.assertRaisesRegex(ValueError, r"^tum_max_dt_s: expected a finite number"):
                occgt.open_dataset(seq, "tum", tum_max_dt_s=bad)
        # The build of a recipe with dataset.tum_max_dt_s, read back by from_split: item 0 is
        # the shard's pair, computed from frames the default tolerance leaves without a pose.
        recipe = os.path.join(root, "r.yaml")
        with open(recipe, "w") as f:
            f.write("name: tum-tolerance\nresolution: [160, 120]\n"
                    f"dataset: {{format: tum, root: {seq}, min_valid_depth_fraction: 0.1, "
                    "tum_max_dt_s: 0.05}\noccupancy: {enabled: false}\n"
                    "sample: {image: png}\nselection: {max_frame_gap: 1}\n")
        split = os.path.join(root, "split")
        common.occgt("build", recipe, "--out", split)
        ds = PairIndexDataset.from_split(split)
        self.assertEqual(ds.tum_max_dt_s, 0.05)
        self.assertGreater(len(ds), 0)
        with open(os.path.join(split, "pairs.jsonl")) as f:
            lines = [json.loads(line) for line in f]
        odd = [i for i, p in enumerate(lines)
               if round(float(p["frame0"]["id"]) * 10) % 2 or round(float(p["frame1"]["id"]) * 10) % 2]
        self.assertTrue(odd, "no pair holds a frame only the wider tolerance gives a pose")
        shards = [s for s in common.read_shard_samples(split, images=False)]
        item = ds[odd[0]]
        np.testing.assert_array_equal(item["label01"].numpy(), shards[odd[0]]["label01"])
        default = PairIndexDataset.from_split(split, tum_max_dt_s=None)
        with self.assertRaisesRegex(ValueError, "no groundtruth within 0.02s"):
            default[odd[0]]


if __name__ == "__main__":
    unittest.main()
