"""A small TUM RGB-D sequence for the tests of the association tolerance
(tests/integration/tum_tolerance_test.py, tests/python/tum_tolerance_test.py)."""
import os

import cv2
import numpy as np


def make_sequence(folder: str) -> str:
    """8 depth frames 0.1 s apart (ids 100.000000 ... 100.700000); a groundtruth entry at each
    even frame's time and 0.03 s after each odd frame's: a camera moving along x in front of
    a wall at 3 m. The default tolerance (0.02 s) leaves the odd frames without a pose; 0.05 s
    gives every frame one. Returns the sequence folder."""
    seq = os.path.join(folder, "rgbd_dataset_freiburg1_test")
    os.makedirs(os.path.join(seq, "depth"), exist_ok=True)
    os.makedirs(os.path.join(seq, "rgb"), exist_ok=True)
    lines = {"depth.txt": [], "rgb.txt": [], "groundtruth.txt": []}
    wall = np.full((480, 640), 3 * 5000, np.uint16)  # 3 m at TUM's 5000 units per metre
    colour = np.random.default_rng(0).integers(0, 255, (480, 640, 3), dtype=np.uint8)
    for i in range(8):
        t = 100.0 + 0.1 * i
        name = f"{t:.6f}"
        cv2.imwrite(os.path.join(seq, "depth", name + ".png"), wall)
        cv2.imwrite(os.path.join(seq, "rgb", name + ".png"), colour)
        lines["depth.txt"].append(f"{name} depth/{name}.png")
        lines["rgb.txt"].append(f"{name} rgb/{name}.png")
        lines["groundtruth.txt"].append(f"{t + (0.03 if i % 2 else 0.0):.4f} {0.05 * i} 0 0 0 0 0 1")
    for name, text in lines.items():
        with open(os.path.join(seq, name), "w") as f:
            f.write("# test\n" + "\n".join(text) + "\n")
    return seq
