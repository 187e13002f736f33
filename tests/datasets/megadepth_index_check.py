"""Reads the LoFTR MegaDepth index written by `occgt build` (loftr_export.kind megadepth) the
way LoFTR's MegaDepth loader does, and compares it with the expectations the C++ test
computed from occgt's reader.

    megadepth_index_check.py LOFTR_DIR ROOT_DIR EXPECTED_JSON

Loader steps reproduced (facts of LoFTR's src/datasets/megadepth.py): the list file names
the scenes (".npz" appended); np.load(npz, allow_pickle=True) gives a dict; pair_infos is
copied and deleted from it and filtered by score > min_overlap_score; a pair is
((idx0, idx1), overlap_score, central_matches); paths are joined to root_dir; K is
scene_info['intrinsics'][idx].copy() reshaped to 3x3; T_0to1 = poses[idx1] @ inv(poses[idx0])."""
import json
import os
import sys

import numpy as np


def main() -> None:
    loftr, root, expected_path = sys.argv[1:4]
    with open(expected_path) as f:
        expected = json.load(f)
    with open(os.path.join(loftr, "train_list.txt")) as f:
        names = [line.split()[0] for line in f.readlines()]
    assert names == sorted(expected), (names, sorted(expected))
    for name in names:
        want = expected[name]
        info = np.load(os.path.join(loftr, "scene_info", name + ".npz"), allow_pickle=True)
        assert isinstance(info, dict), type(info)
        assert list(info) == ["image_paths", "depth_paths", "intrinsics", "poses", "pair_infos"]
        pair_infos = info["pair_infos"].copy()
        del info["pair_infos"]
        pair_infos = [p for p in pair_infos if p[1] > 0.0]
        assert info["image_paths"] == want["image_paths"], (info["image_paths"], want)
        assert info["depth_paths"] == want["depth_paths"], (info["depth_paths"], want)
        for k, (K, K_want) in enumerate(zip(info["intrinsics"], want["intrinsics"])):
            if K_want is None:
                assert K is None, (name, k)
                continue
            K = np.array(K.copy(), dtype=np.float64).reshape(3, 3)
            assert np.allclose(K, K_want, rtol=0, atol=1e-12), (name, k, K, K_want)
        for k, (T, T_want) in enumerate(zip(info["poses"], want["poses"])):
            assert (T is None) == (T_want is None), (name, k)
            if T is not None:
                assert np.allclose(np.array(T), T_want, rtol=0, atol=1e-12), (name, k)
        got = [((int(i), int(j)), float(s), c) for (i, j), s, c in pair_infos]
        assert [(ij, c) for ij, _, c in got] == [(tuple(p[0]), []) for p in want["pairs"]], got
        for (_, s, _), p in zip(got, want["pairs"]):
            assert abs(s - p[1]) < 1e-12, (s, p)
        for (i, j), _, _ in got:
            for k in (i, j):  # (the fixture writes only some colour images)
                assert os.path.isfile(os.path.join(root, info["depth_paths"][k])), k
            T0, T1 = np.array(info["poses"][i]), np.array(info["poses"][j])
            T_0to1 = np.matmul(T1, np.linalg.inv(T0))
            assert np.allclose(T_0to1[3], [0, 0, 0, 1])
    print("ok", len(names))


if __name__ == "__main__":
    main()
