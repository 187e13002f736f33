"""occgt.torch.loftr_supervision against a straightforward re-implementation of LoFTR's
coarse supervision in torch (written here from the facts of LoFTR's `spvs_coarse` and
`warp_kpts`; docs/PYTHON.md, "Supervision"), on the real 7-Scenes and TartanAir samples
(../shared/data, required) and on synthetic scenes of `occgt synth`:
- compat=True: every id bit-equal, every warped point within float tolerance, on every pair;
- default: equal to the reference wherever no fix applies; the cells the fixes change are
  exactly those without depth, behind the other camera or out of the grid (plus cell 0,
  which LoFTR ignores);
- mode="occ2net": the vv/vo/ov matches of occgt.pair_ground_truth, from padded and from
  concatenated batches (occgt.torch.collate) and computed on the fly, with their fine targets;
  K in COLMAP's convention (LoFTR's MegaDepth batches) gives the matches of occgt's K;
  stored matches refuse the options that compute matches, and a coarse_stride or anchor
  other than theirs (also over ShardDataset batches of built 7-Scenes splits).
The reference runs in float64 (LoFTR's float32 depends on the BLAS's summation order; occgt
computes in double), then rounds the warped points to float32 as LoFTR's tensors are; run in
float32 (LoFTR's arithmetic) its cells may differ only next to a rounding boundary."""
from __future__ import annotations

import os
import sys
import unittest
from typing import Any, Dict, List, Optional, Sequence, Tuple

import numpy as np
import torch

sys.path.insert(0, os.path.dirname(__file__))
import common  # noqa: E402

import occgt  # noqa: E402
from occgt.torch import loftr_supervision  # noqa: E402
from occgt.torch.supervision import PADDED_CELL, loftr_fine_target  # noqa: E402
from occgt.torch.collate import Collate  # noqa: E402

torch.set_num_threads(1)


# ---- The reference: LoFTR's coarse supervision, re-implemented from its facts. ----

def _grid(n: int, h: int, w: int, spacing: torch.Tensor) -> torch.Tensor:
    """Corner grid points (c, r) · spacing [N, 2] (float32), [N, h·w, 2], row-major."""
    rows, cols = torch.meshgrid(torch.arange(h), torch.arange(w), indexing="ij")
    cells = torch.stack([cols, rows], -1).reshape(1, h * w, 2).to(torch.float32)
    return spacing[:, None, :] * cells.expand(n, -1, -1)


def _warp(pts: torch.Tensor, depth_a: torch.Tensor, b_from_a: torch.Tensor, K_a: torch.Tensor,
          K_b: torch.Tensor, f64: torch.dtype = torch.float64
          ) -> Tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """LoFTR's warp_kpts without its mask: (warped float32 [N, L, 2], z in B [N, L], the
    source depth [N, L]), computed in f64 (float32: LoFTR's own arithmetic)."""
    pix = pts.round().long()
    d = torch.stack([depth_a[b, pix[b, :, 1], pix[b, :, 0]] for b in range(pts.shape[0])])
    homog = torch.cat([pts.to(f64), torch.ones_like(pts[..., :1], dtype=f64)], -1)
    in_a = torch.linalg.inv(K_a.to(f64)) @ (homog * d.to(f64)[..., None]).transpose(1, 2)
    in_b = b_from_a[:, :3, :3].to(f64) @ in_a + b_from_a[:, :3, 3:].to(f64)
    proj = (K_b.to(f64) @ in_b).transpose(1, 2)
    warped = proj[..., :2] / (proj[..., 2:] + 1e-4)
    return warped.to(torch.float32), in_b[:, 2, :], d


def _nearest(warped: torch.Tensor, spacing: torch.Tensor, h: int, w: int
             ) -> Tuple[torch.Tensor, torch.Tensor]:
    """(cell index, in-grid mask) of the nearest corner: round(warped / spacing) in float32.
    Bounds are tested on the rounded floats (LoFTR converts to int64 first; the same for
    every finite value in range, and NaN/huge values are out of bounds either way)."""
    r = (warped / spacing[:, None, :]).round()
    inside = (r[..., 0] >= 0) & (r[..., 0] < w) & (r[..., 1] >= 0) & (r[..., 1] < h)
    r = torch.where(inside[..., None], r, torch.zeros_like(r)).long()
    return r[..., 0] + r[..., 1] * w, inside


def reference_supervision(batch: Dict[str, torch.Tensor], fixes: bool, stride: int = 8,
                          dtype: torch.dtype = torch.float64,
                          with_status: bool = True, dense: bool = True) -> Dict[str, Any]:
    """fixes=False: LoFTR's spvs_coarse. fixes=True: the same with occgt's three fixes
    (no depth, behind, out of grid → no target; cell 0 an ordinary cell). dtype: of the
    warp; with_status=False (only with fixes=False) skips the per-cell status, which LoFTR
    does not compute (tests/bench/supervision_bench.py times LoFTR's work in float32);
    dense=False skips conf_matrix_gt (None)."""
    depth0, depth1 = batch["depth0"], batch["depth1"]
    n = depth0.shape[0]
    H0, W0 = batch["image0"].shape[2:] if "image0" in batch else depth0.shape[1:]
    H1, W1 = batch["image1"].shape[2:] if "image1" in batch else depth1.shape[1:]
    h0, w0, h1, w1 = H0 // stride, W0 // stride, H1 // stride, W1 // stride
    ones = torch.ones(n, 2)
    s0 = stride * batch.get("scale0", ones).to(torch.float32)
    s1 = stride * batch.get("scale1", ones).to(torch.float32)
    pt0, pt1 = _grid(n, h0, w0, s0), _grid(n, h1, w1, s1)
    # Padded images (LoFTR's MegaDepth mask0/mask1 at the coarse grid, 0 on padding).
    pad0 = pad1 = None
    if "mask0" in batch:
        pad0 = ~batch["mask0"].bool().reshape(n, h0 * w0)
        pad1 = ~batch["mask1"].bool().reshape(n, h1 * w1)
        if not fixes:  # LoFTR: padded grid points become (0, 0) and are warped as any other
            pt0, pt1 = pt0.clone(), pt1.clone()
            pt0[pad0] = 0.0
            pt1[pad1] = 0.0
    w_pt0, z0, d0 = _warp(pt0, depth0, batch["T_0to1"], batch["K0"], batch["K1"], dtype)
    w_pt1, z1, d1 = _warp(pt1, depth1, batch["T_1to0"], batch["K1"], batch["K0"], dtype)
    idx1, in1 = _nearest(w_pt0, s1, h1, w1)
    idx0, in0 = _nearest(w_pt1, s0, h0, w0)
    status = []
    for d, z, inside in ((d0, z0, in1), (d1, z1, in0)) if with_status or fixes else ():
        s = torch.full(d.shape, 3, dtype=torch.uint8)
        s[inside] = 0
        s[z <= 0] = 2
        s[~(torch.isfinite(d) & (d > 0))] = 1
        status.append(s)
    if fixes and pad0 is not None:
        # occgt: a target on the other image's padding is out of the grid; a padded cell
        # has no target (status 4).
        for s, idx, pad_own, pad_other in ((status[0], idx1, pad0, pad1),
                                           (status[1], idx0, pad1, pad0)):
            s[(s == 0) & torch.gather(pad_other, 1, idx)] = 3
            s[pad_own] = 4
    if fixes:
        idx1 = torch.where(status[0] == 0, idx1, torch.full_like(idx1, -1))
        idx0 = torch.where(status[1] == 0, idx0, torch.full_like(idx0, -1))
        back = torch.gather(idx0, 1, idx1.clamp(min=0))
        correct = (idx1 >= 0) & (back == torch.arange(h0 * w0)[None])
    else:
        back = torch.stack([idx0[b][idx1[b]] for b in range(n)])
        correct = back == torch.arange(h0 * w0)[None].repeat(n, 1)
        correct[:, 0] = False  # LoFTR ignores the top-left cell
    b_ids, i_ids = torch.where(correct)
    j_ids = idx1[b_ids, i_ids]
    conf = torch.zeros(n, h0 * w0, h1 * w1) if dense else None
    if conf is not None:
        conf[b_ids, i_ids, j_ids] = 1
    if not fixes and b_ids.numel() == 0:
        b_ids = i_ids = j_ids = torch.zeros(1, dtype=torch.int64)
    return {"conf_matrix_gt": conf, "spv_b_ids": b_ids, "spv_i_ids": i_ids, "spv_j_ids": j_ids,
            "spv_w_pt0_i": w_pt0, "spv_pt1_i": pt1, "spv_w_pt1_i": w_pt1, "spv_pt0_i": pt0,
            "status": status, "target0": idx1, "target1": idx0}


# ---- Batches from the datasets. ----

def make_batch(frames: Sequence[Tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
                                      np.ndarray]]) -> Dict[str, torch.Tensor]:
    """LoFTR's batch of pairs (d0, K0, world_from_cam0, d1, K1, world_from_cam1): float32
    tensors, T_0to1 = cam1_from_cam0 (float64 product rounded), T_1to0 its float32 inverse
    (as LoFTR's ScanNet dataset)."""
    keys: Dict[str, List[torch.Tensor]] = {k: [] for k in ("depth0", "depth1", "K0", "K1",
                                                            "T_0to1", "T_1to0")}
    for d0, K0, P0, d1, K1, P1 in frames:
        T = torch.from_numpy(np.linalg.inv(P1) @ P0).to(torch.float32)
        keys["depth0"].append(torch.from_numpy(d0))
        keys["depth1"].append(torch.from_numpy(d1))
        keys["K0"].append(torch.from_numpy(K0).to(torch.float32))
        keys["K1"].append(torch.from_numpy(K1).to(torch.float32))
        keys["T_0to1"].append(T)
        keys["T_1to0"].append(torch.linalg.inv(T))
    return {k: torch.stack(v) for k, v in keys.items()}


def scene_pairs(scene: occgt.Scene, pairs: Sequence[Tuple[str, str]], width: int = 640,
                height: int = 480) -> List[Tuple[np.ndarray, ...]]:
    out = []
    for a, b in pairs:
        d0, K0, P0 = scene.load(a, width, height)
        d1, K1, P1 = scene.load(b, width, height)
        out.append((d0, K0, P0, d1, K1, P1))
    return out


def colmap_k(batch: Dict[str, torch.Tensor]) -> Dict[str, torch.Tensor]:
    """The batch with K0/K1 in COLMAP's pixel convention (pixel centres at +0.5: cx, cy
    0.5 higher), as LoFTR's MegaDepth loader gives them."""
    out = dict(batch)
    for key in ("K0", "K1"):
        out[key] = batch[key].clone()
        out[key][:, :2, 2] += 0.5
    return out


def stored_samples(frames: Sequence[Tuple[np.ndarray, ...]], **options: Any
                   ) -> Tuple[List[Dict[str, torch.Tensor]], List[Dict[str, Any]]]:
    """Samples of the sample contract holding occgt.pair_ground_truth's matches of each pair
    (preset occ2net, `options`), and the results."""
    samples, results = [], []
    for d0, K0, P0, d1, K1, P1 in frames:
        r = occgt.pair_ground_truth(d0, d1, K0, K1, P0, P1, "occ2net", **options)
        results.append(r)
        samples.append({"depth0": torch.from_numpy(d0), "depth1": torch.from_numpy(d1),
                        "K0": torch.from_numpy(K0).float(), "K1": torch.from_numpy(K1).float(),
                        "T_0to1": torch.from_numpy(r["T_0to1"]).float(),
                        "matches": torch.from_numpy(r["matches"]).long(),
                        "match_type": torch.from_numpy(r["match_type"]).long(),
                        "match_xy": torch.from_numpy(r["match_xy"])})
    return samples, results


def ids(out: Dict[str, Any]) -> List[Tuple[int, int, int]]:
    return list(zip(out["spv_b_ids"].tolist(), out["spv_i_ids"].tolist(),
                    out["spv_j_ids"].tolist()))


class Checks:
    """Assertions shared by the data sets (a mixin of unittest.TestCase)."""

    def check_batch(self: Any, batch: Dict[str, torch.Tensor], where: str) -> Dict[str, int]:
        ref = reference_supervision(batch, fixes=False)
        got = loftr_supervision(batch, compat=True)
        # compat: LoFTR exactly.
        self.assertEqual(ids(got), ids(ref), f"{where}: compat ids")
        for key in ("spv_pt1_i", "spv_pt0_i"):
            self.assertTrue(torch.equal(got[key], ref[key]), f"{where}: {key}")
        for key in ("spv_w_pt0_i", "spv_w_pt1_i"):
            finite = torch.isfinite(ref[key])
            self.assertTrue(torch.equal(finite, torch.isfinite(got[key])), f"{where}: {key}")
            err = (got[key][finite] - ref[key][finite]).abs()
            tol = 1e-5 * ref[key][finite].abs().clamp(min=1.0)
            self.assertTrue(bool((err <= tol).all()), f"{where}: {key} max err {err.max()}")
        self.assertTrue(torch.equal(got["conf_matrix_gt"], ref["conf_matrix_gt"]), where)
        self.assertTrue(torch.equal(got["spv_status0"], ref["status"][0]), f"{where}: status0")
        self.assertTrue(torch.equal(got["spv_status1"], ref["status"][1]), f"{where}: status1")
        # Default: the reference with the fixes, and the difference from LoFTR is exactly the
        # matches that touch a fixed cell or cell 0.
        fixed_ref = reference_supervision(batch, fixes=True)
        fixed = loftr_supervision(batch)
        self.assertEqual(ids(fixed), ids(fixed_ref), f"{where}: default ids")
        self.assertTrue(torch.equal(fixed["spv_status0"], fixed_ref["status"][0]), where)
        self.assertTrue(torch.equal(fixed["spv_status1"], fixed_ref["status"][1]), where)
        ok0 = fixed["spv_status0"] == 0
        ok1 = fixed["spv_status1"] == 0
        for key, ok in (("spv_w_pt0_i", ok0), ("spv_w_pt1_i", ok1)):
            # Untouched cells: LoFTR's warped points, bit for bit with compat.
            self.assertTrue(torch.equal(fixed[key][ok], got[key][ok]), f"{where}: {key}")
        nd_or_behind = ((fixed["spv_status0"] == 1) | (fixed["spv_status0"] == 2) |
                        (fixed["spv_status0"] == 4))
        self.assertTrue(bool(torch.isnan(fixed["spv_w_pt0_i"][nd_or_behind]).all()), where)
        loftr_set, occgt_set = set(ids(ref)), set(ids(fixed))
        if ref["spv_b_ids"].numel() == 1 and not ref["conf_matrix_gt"].any():
            loftr_set = set()  # LoFTR's dummy match
        for b, i, j in loftr_set - occgt_set:  # dropped: a fixed cell on either side
            self.assertTrue(not ok0[b, i] or not ok1[b, j], f"{where}: dropped ({b}, {i}, {j})")
        for b, i, j in occgt_set - loftr_set:  # added: only cell 0, which LoFTR ignores
            self.assertEqual(i, 0, f"{where}: added ({b}, {i}, {j})")
        for b, i, j in occgt_set:
            self.assertTrue(ok0[b, i] and ok1[b, j], where)
        for b, i, j in loftr_set & set((b, i, j) for b, i, j in loftr_set
                                       if ok0[b, i] and ok1[b, j]):
            self.assertIn((b, i, j), occgt_set, where)
        # Fine target: within the window (|w − corner| <= 4 px → <= 1 with scale 1).
        if "scale1" not in batch and fixed["spv_b_ids"].numel():
            self.assertLessEqual(float(fixed["expec_f_gt"].abs().max()), 1.0 + 1e-6, where)
        st = torch.cat([fixed["spv_status0"].flatten(), fixed["spv_status1"].flatten()])
        return {"matches": len(occgt_set), "loftr": len(loftr_set),
                "no_depth": int((st == 1).sum()), "behind": int((st == 2).sum()),
                "out_of_grid": int((st == 3).sum()), "padded": int((st == 4).sum())}


class SevenScenes(unittest.TestCase, Checks):
    @classmethod
    def setUpClass(cls) -> None:
        ds = occgt.open_dataset(common.shared("sevenscenes"), "sevenscenes")
        cls.scene = ds.scene(ds.scenes()[0])
        ids_ = [f.id for f in cls.scene.frames]
        cls.pairs = [(ids_[k], ids_[k + g]) for k, g in ((0, 5), (0, 10), (10, 20), (20, 25),
                                                           (30, 19), (5, 40), (45, 4))]
        cls.frames = scene_pairs(cls.scene, cls.pairs)

    def test_every_pair(self) -> None:
        total: Dict[str, int] = {}
        for k, frames in enumerate(self.frames):
            c = self.check_batch(make_batch([frames]), f"7-Scenes {self.pairs[k]}")
            for key, v in c.items():
                total[key] = total.get(key, 0) + v
        self.assertGreater(total["matches"], 5000)  # not vacuous
        self.assertGreater(total["no_depth"], 100)  # the no-depth fix is exercised
        self.assertGreater(total["out_of_grid"], 100)
        self.assertNotEqual(total["matches"], total["loftr"])

    def test_loftr_float32(self) -> None:
        """LoFTR's own float32 arithmetic: its target cells are occgt's (compat) except where
        the warped point lies within 1e-3 cells of a rounding boundary, and its matches
        differ only at those cells."""
        cells = differ = 0
        for k, frames in enumerate(self.frames):
            batch = make_batch([frames])
            ref32 = reference_supervision(batch, fixes=False, dtype=torch.float32)
            got = loftr_supervision(batch, compat=True)
            flipped = []
            for side, key in ((0, "spv_w_pt0_i"), (1, "spv_w_pt1_i")):
                one = occgt._occgt.loftr_coarse_supervision(
                    *(batch[n][0].numpy() for n in ("depth0", "depth1", "K0", "K1", "T_0to1",
                                                    "T_1to0")), compat=True)
                target = torch.from_numpy(one[f"target{side}"]).long()[None]
                diff = ref32[f"target{side}"] != target
                at = got[key][diff] / 8.0
                near = ((at - at.floor() - 0.5).abs() < 1e-3).any(-1)
                self.assertTrue(bool(near.all()), f"{self.pairs[k]}: side {side}: {at[~near]}")
                flipped.append(diff[0])
                cells += diff.numel()
                differ += int(diff.sum())
            for b, i, j in set(ids(got)) ^ set(ids(ref32)):
                self.assertTrue(bool(flipped[0][i] or flipped[1][j]), f"{self.pairs[k]}")
        self.assertLessEqual(differ, cells * 1e-3)

    def test_batched_equals_per_pair(self) -> None:
        batch = make_batch(self.frames[:4])
        self.check_batch(batch, "7-Scenes batch of 4")
        whole = loftr_supervision(batch)
        for b in range(4):
            one = loftr_supervision(make_batch([self.frames[b]]))
            sel = whole["spv_b_ids"] == b
            self.assertTrue(torch.equal(whole["spv_i_ids"][sel], one["spv_i_ids"]))
            self.assertTrue(torch.equal(whole["spv_j_ids"][sel], one["spv_j_ids"]))
            self.assertTrue(torch.equal(whole["expec_f_gt"][sel], one["expec_f_gt"]))
            self.assertTrue(torch.equal(whole["conf_matrix_gt"][b], one["conf_matrix_gt"][0]))

    def test_behind_the_camera(self) -> None:
        """Camera 1 turned by 90 degrees about y and moved back: part of the scene lies
        behind it; LoFTR mirrors those points into view, occgt gives them no match."""
        d0, K0, P0, _, _, _ = self.frames[0]
        turn = np.eye(4)
        turn[:3, :3] = [[0, 0, 1], [0, 1, 0], [-1, 0, 0]]
        turn[:3, 3] = [0.5, 0.0, -1.0]
        P1 = P0 @ turn
        batch = make_batch([(d0, K0, P0, d0, K0, P1)])
        c = self.check_batch(batch, "7-Scenes turned")
        self.assertGreater(c["behind"], 500)

    def test_image_scale(self) -> None:
        """LoFTR's resized images: depth 640x480, image 320x240, scale (2, 2): grid points
        every 16 depth pixels, cells of the 40x30 grid, the fine target divided by 2·2."""
        batch = make_batch(self.frames[:2])
        batch["image0"] = torch.zeros(2, 1, 240, 320)
        batch["image1"] = torch.zeros(2, 1, 240, 320)
        batch["scale0"] = torch.full((2, 2), 2.0)
        batch["scale1"] = torch.full((2, 2), 2.0)
        self.check_batch(batch, "7-Scenes scale 2")
        out = loftr_supervision(batch)
        self.assertEqual(tuple(out["conf_matrix_gt"].shape), (2, 1200, 1200))
        self.assertEqual(out["spv_pt1_i"][0, 41].tolist(), [16.0, 16.0])
        b, i, j = out["spv_b_ids"], out["spv_i_ids"], out["spv_j_ids"]
        want = (out["spv_w_pt0_i"][b, i] - out["spv_pt1_i"][b, j]) / 4.0 / 2
        self.assertTrue(torch.allclose(out["expec_f_gt"], want))
        self.assertTrue(torch.equal(
            loftr_fine_target(out, b, i, j, scale1=batch["scale1"]), out["expec_f_gt"]))
        # At any ids (a coarse matcher's): NaN at cells without depth.
        no_depth = torch.nonzero(out["spv_status0"][0] == 1)[:1, 0]
        f = loftr_fine_target(out, torch.zeros(1, dtype=torch.long), no_depth,
                              torch.zeros(1, dtype=torch.long), scale1=batch["scale1"])
        self.assertTrue(bool(torch.isnan(f).all()) and no_depth.numel() == 1)
        self.assertLessEqual(float(out["expec_f_gt"].abs().max()), 1.0 + 1e-6)

    def test_padded_megadepth_batch(self) -> None:
        """LoFTR's MegaDepth batches: images and depth zero-padded (here 640x480 to 640x640
        and 704x480), mask0/mask1 [N, h_c, w_c] at the coarse grid. compat: LoFTR's
        mask_pts_at_padded_regions (padded grid points warped from (0, 0)); default: no
        match touches the padding."""
        frames = self.frames[:2]
        batch = make_batch(frames)
        n = 2
        depth0 = torch.zeros(n, 640, 640)
        depth0[:, :480, :] = batch["depth0"]
        depth1 = torch.zeros(n, 480, 704)
        depth1[:, :, :640] = batch["depth1"]
        batch["depth0"], batch["depth1"] = depth0, depth1
        batch["image0"] = torch.zeros(n, 1, 640, 640)
        batch["image1"] = torch.zeros(n, 1, 480, 704)
        mask0 = torch.zeros(n, 80, 80, dtype=torch.bool)
        mask0[:, :60, :] = True
        mask1 = torch.zeros(n, 60, 88, dtype=torch.bool)
        mask1[:, :, :80] = True
        batch["mask0"], batch["mask1"] = mask0, mask1
        c = self.check_batch(batch, "7-Scenes padded")
        self.assertEqual(c["padded"], n * (20 * 80 + 60 * 8))
        self.assertGreater(c["matches"], 1000)
        compat = loftr_supervision(batch, compat=True)
        fixed = loftr_supervision(batch)
        pad0 = ~mask0.reshape(n, -1)
        # compat: the padded cells' grid points are (0, 0) and their warps are cell 0's.
        self.assertTrue(bool((compat["spv_pt0_i"][pad0] == 0).all()))
        w = compat["spv_w_pt0_i"]
        self.assertTrue(torch.equal(w[pad0], w[:, :1].expand(-1, 6400, -1)[pad0]))
        # default: the padded cells keep their corners, warp to NaN, and no match uses them.
        self.assertEqual(fixed["spv_pt0_i"][0, 60 * 80].tolist(), [0.0, 480.0])
        self.assertTrue(bool(torch.isnan(fixed["spv_w_pt0_i"][pad0]).all()))
        b, i, j = fixed["spv_b_ids"], fixed["spv_i_ids"], fixed["spv_j_ids"]
        self.assertFalse(bool(pad0[b, i].any()))
        self.assertFalse(bool((~mask1.reshape(n, -1))[b, j].any()))
        # The same pairs unpadded: the same matches (the padding holds no depth and no cell
        # of the image lands on it except through no-depth points).
        plain = loftr_supervision(make_batch(frames))
        unpadded = {(bb, ii // 80 * 80 + ii % 80, jj // 80 * 88 + jj % 80)
                    for bb, ii, jj in ids(plain)}
        self.assertEqual(set(ids(fixed)), unpadded)
        for bad, key in (({"mask0": mask0[:, :10]}, "mask0"),
                         ({"mask1": mask1.float()[:1]}, "mask1")):
            with self.assertRaisesRegex(ValueError, key):
                loftr_supervision({**batch, **bad})
        only = dict(batch)
        del only["mask1"]
        with self.assertRaisesRegex(ValueError, "mask1"):
            loftr_supervision(only)

    def test_occ2net_resized_and_padded(self) -> None:
        """mode="occ2net" on LoFTR's resized (scale 2) and padded (MegaDepth-style) batches,
        whose K0/K1 are in COLMAP's pixel convention (LoFTR's MegaDepth loader): the matches
        of occgt.pair_ground_truth on the frames loaded at the image's size by the dataset
        reader (Scene.load at 320x240, another path to the same resampling), with the cells
        placed on the padded grids; occgt's K with k_convention="occgt" gives the same."""
        pairs = self.pairs[:2]
        small = scene_pairs(self.scene, pairs, 320, 240)
        rs = [occgt.pair_ground_truth(d0, d1, K0, K1, P0, P1, "occ2net")
              for d0, K0, P0, d1, K1, P1 in small]
        n = 2
        plain = make_batch(self.frames[:2])  # depth 640x480, occgt's K
        plain["image0"] = torch.zeros(n, 1, 240, 320)
        plain["image1"] = torch.zeros(n, 1, 240, 320)
        plain["scale0"] = torch.full((n, 2), 2.0)
        plain["scale1"] = torch.full((n, 2), 2.0)
        batch = colmap_k(plain)
        out = loftr_supervision(batch, "occ2net", preset="occ2net")
        want = [(b, i, j) for b, r in enumerate(rs) for i, j in r["matches"].tolist()]
        self.assertEqual(ids(out), want)
        occgt_k = loftr_supervision(plain, "occ2net", preset="occ2net", k_convention="occgt")
        self.assertEqual(ids(occgt_k), want)
        self.assertTrue(torch.equal(occgt_k["spv_xy"], out["spv_xy"]))
        # COLMAP's K read as occgt's (the default before k_convention): other matches.
        shifted = loftr_supervision(batch, "occ2net", preset="occ2net", k_convention="occgt")
        self.assertNotEqual(ids(shifted), want)
        self.assertGreater(len(want), 500)
        types = np.concatenate([r["match_type"] for r in rs])
        self.assertTrue(np.array_equal(out["spv_type"].numpy(), types))
        self.assertGreater(int((types == occgt.VO).sum()), 5)
        self.assertTrue(np.allclose(out["spv_xy"].numpy(),
                                    np.concatenate([r["match_xy"] for r in rs]), atol=1e-3))
        self.assertEqual(tuple(out["conf_matrix_gt"].shape), (n, 1200, 1200))
        # Padded: image 0 to 320x320 (40x40 cells), image 1 to 352x240 (44x30), depth
        # zero-padded at the bottom/right; same matches, cells renumbered on the wider grids.
        padded = dict(batch)
        d0 = torch.zeros(n, 700, 640)
        d0[:, :480] = batch["depth0"]
        d1 = torch.zeros(n, 480, 720)
        d1[:, :, :640] = batch["depth1"]
        padded["depth0"], padded["depth1"] = d0, d1
        padded["image0"] = torch.zeros(n, 1, 320, 320)
        padded["image1"] = torch.zeros(n, 1, 240, 352)
        mask0 = torch.zeros(n, 40, 40, dtype=torch.bool)
        mask0[:, :30] = True
        mask1 = torch.zeros(n, 30, 44, dtype=torch.bool)
        mask1[:, :, :40] = True
        padded["mask0"], padded["mask1"] = mask0, mask1
        got = loftr_supervision(padded, "occ2net", preset="occ2net")  # K: COLMAP's (mask0)
        self.assertTrue(torch.equal(
            loftr_supervision({**padded, **{k: plain[k] for k in ("K0", "K1")}}, "occ2net",
                              preset="occ2net", k_convention="occgt")["spv_xy"], got["spv_xy"]))
        self.assertEqual(ids(got), [(b, i, j // 40 * 44 + j % 40) for b, i, j in want])
        self.assertTrue(torch.equal(got["spv_xy"], out["spv_xy"]))
        self.assertTrue(torch.equal(got["expec_f_gt"], out["expec_f_gt"]))
        self.assertEqual(tuple(got["conf_matrix_gt"].shape), (n, 1600, 1320))
        cells1 = got["spv_cells1"].reshape(n, 30, 44)
        self.assertTrue(bool((cells1[:, :, 40:] == PADDED_CELL).all()))
        self.assertTrue(torch.equal(cells1[:, :, :40].reshape(n, -1), out["spv_cells1"]))
        self.assertTrue(bool((got["spv_cells0"].reshape(n, 40, 40)[:, 30:] == PADDED_CELL).all()))
        # Bad input, each naming what is wrong.
        holes = mask1.clone()
        holes[:, 3, 5] = False
        for change, text in (({"mask1": holes}, "mask1"),
                             ({"image1": None}, "image1"),
                             ({"scale1": torch.full((n, 2), 3.0)}, "scale"),
                             ({"matches": torch.zeros(n, 1, 2)}, "matches")):
            with self.subTest(text=text):
                b = dict(padded)
                for k, v in change.items():
                    if v is None:
                        del b[k]
                    else:
                        b[k] = v
                with self.assertRaisesRegex(ValueError, text):
                    loftr_supervision(b, "occ2net")

    def test_depth_at_image_size(self) -> None:
        """occgt.depth_at_image_size on a 4x4 map at scale 2: pixel u' takes source pixel
        floor((u' + 0.5) * 2) = 1, 3; fx' = fx / 2, cx' = (cx + 0.5) / 2 - 0.5."""
        depth = np.arange(1, 17, dtype=np.float32).reshape(4, 4)
        K = np.array([[100.0, 0, 1.5], [0, 80.0, 1.5], [0, 0, 1]])
        d, k = occgt.depth_at_image_size(depth, K, (2.0, 2.0), 2, 2)
        self.assertEqual(d.tolist(), [[6.0, 8.0], [14.0, 16.0]])
        self.assertTrue(np.allclose(k, [[50.0, 0, 0.5], [0, 40.0, 0.5], [0, 0, 1]]))
        # A padded map: only the covered top-left part is read.
        padded = np.zeros((6, 9), np.float32)
        padded[:4, :4] = depth
        d2, k2 = occgt.depth_at_image_size(padded, K, (2.0, 2.0), 2, 2)
        self.assertTrue(np.array_equal(d2, d) and np.array_equal(k2, k))
        for args, text in ((((2.0, 2.0), 3, 2), "scale"), (((0.0, 2.0), 2, 2), "scale"),
                           (((2.0, 2.0), 1, 2), "width")):
            with self.assertRaisesRegex(ValueError, text):
                occgt.depth_at_image_size(depth, K, *args)

    def test_options_and_bad_input(self) -> None:
        batch = make_batch(self.frames[:1])
        sparse = loftr_supervision(batch, dense_conf_matrix=False)
        dense = loftr_supervision(batch)
        self.assertTrue(sparse["conf_matrix_gt"].is_sparse)
        self.assertTrue(torch.equal(sparse["conf_matrix_gt"].to_dense(), dense["conf_matrix_gt"]))
        coarse16 = loftr_supervision(batch, coarse_stride=16)
        self.assertEqual(coarse16["spv_pt1_i"].shape[1], 40 * 30)
        self.assertEqual(coarse16["spv_pt1_i"][0, 1].tolist(), [16.0, 0.0])
        ref16 = reference_supervision(batch, fixes=True, stride=16)
        self.assertEqual(ids(coarse16), ids(ref16))
        fine = loftr_supervision(batch, fine_stride=4, fine_window=7)
        self.assertTrue(torch.allclose(fine["expec_f_gt"] * 4 * 3, dense["expec_f_gt"] * 2 * 2))
        # A T_1to0 that is not T_0to1's inverse (it gave 0 matches, silently); a MegaDepth-
        # scale translation in float32 is still the inverse.
        wrong = dict(batch)
        wrong["T_1to0"] = batch["T_1to0"].clone()
        wrong["T_1to0"][0, 0, 3] += 0.05
        with self.assertRaisesRegex(ValueError, r"^T_1to0: expected the inverse of T_0to1"):
            loftr_supervision(wrong)
        big = np.eye(4)
        big[:3, :3] = np.array([[0.6, -0.8, 0], [0.8, 0.6, 0], [0, 0, 1]])
        big[:3, 3] = [3e4, -2e4, 1e4]
        occgt._occgt.loftr_coarse_supervision(
            batch["depth0"][0].numpy(), batch["depth1"][0].numpy(), batch["K0"][0].numpy(),
            batch["K1"][0].numpy(), big.astype(np.float32),
            np.linalg.inv(big.astype(np.float32)).astype(np.float32))
        # No match at all: empty ids; compat gives LoFTR's dummy (0, 0, 0).
        far = dict(batch)
        far["T_0to1"] = batch["T_0to1"].clone()
        far["T_0to1"][:, 0, 3] += 100.0
        far["T_1to0"] = torch.linalg.inv(far["T_0to1"])
        self.assertEqual(loftr_supervision(far)["spv_b_ids"].numel(), 0)
        dummy = loftr_supervision(far, compat=True)
        self.assertEqual(ids(dummy), [(0, 0, 0)])
        self.assertFalse(bool(dummy["conf_matrix_gt"].any()))
        # Without T_1to0 the exact inverse of T_0to1 is used.
        no_inv = {k: v for k, v in batch.items() if k != "T_1to0"}
        self.assertGreater(loftr_supervision(no_inv)["spv_b_ids"].numel(), 1000)
        cases = [
            (dict(mode="superglue"), None, "mode"),
            (dict(coarse_stride=0), None, "coarse_stride"),
            (dict(fine_window=2), None, "fine_window"),
            (dict(abs_tol_m=0.1), None, "abs_tol_m"),
            ({}, {"depth0": None}, "depth0"),
            ({}, {"K0": torch.zeros(1, 3, 3)}, "K0"),
            ({}, {"K1": torch.eye(4)[None]}, "K1"),
            ({}, {"T_0to1": torch.full((1, 4, 4), float("nan"))}, "T_0to1"),
            ({}, {"T_1to0": 2 * torch.eye(4)[None]}, "T_1to0"),
            ({}, {"mask0": torch.ones(1, 60, 80)}, "mask0"),
            ({}, {"depth1": torch.zeros(2, 480, 640)}, "depth1"),
        ]
        # The binding itself (one pair, NumPy).
        one = [batch[k][0].numpy() for k in ("depth0", "depth1", "K0", "K1", "T_0to1")]
        binding_cases = [
            (dict(scale0=(0.0, 1.0)), "scale0"),
            (dict(image_size1=(4, 640)), "image_size1"),
            (dict(coarse_stride=2000), "coarse_stride"),
            (dict(compat=True, image_size0=(960, 1280)), "depth0"),  # grid off the depth map
            (dict(mask0=np.ones((60, 79), bool)), "mask0"),  # not the 60x80 coarse grid
            (dict(mask1=np.ones((60, 80), np.float32)), "mask1"),  # not bool/integer
        ]
        for kwargs, name in binding_cases:
            with self.subTest(binding=name):
                with self.assertRaises(ValueError) as e:
                    occgt._occgt.loftr_coarse_supervision(*one, **kwargs)
                self.assertTrue(str(e.exception).startswith(name + ":"), str(e.exception))
        # Depth layouts (read in place when float32 C-contiguous, else converted): same result.
        ref_one = occgt._occgt.loftr_coarse_supervision(*one)
        padded = np.zeros((480, 1280), np.float32)
        padded[:, ::2] = one[0]
        for name, d in (("float64", one[0].astype(np.float64)), ("fortran", np.asfortranarray(
                one[0])), ("strided", padded[:, ::2]), ("big-endian", one[0].astype(">f4"))):
            with self.subTest(layout=name):
                r = occgt._occgt.loftr_coarse_supervision(d, *one[1:])
                for key in ("warped0", "warped1", "target0", "target1", "matches"):
                    self.assertTrue(np.array_equal(r[key], ref_one[key], equal_nan=True), key)
        with self.assertRaises(ValueError) as e:
            occgt._occgt.loftr_coarse_supervision(one[0].astype(np.int32), *one[1:])
        self.assertTrue(str(e.exception).startswith("depth0: expected a depth map"))
        for kwargs, change, name in cases:
            with self.subTest(name=name):
                b = dict(batch)
                for k, v in (change or {}).items():
                    if v is None:
                        del b[k]
                    else:
                        b[k] = v
                with self.assertRaises(ValueError) as e:
                    loftr_supervision(b, **kwargs)
                self.assertIn(name, str(e.exception))

    def test_occ2net_colmap_k(self) -> None:
        """A LoFTR-MegaDepth-like batch of a pair whose answer is known: depth and images at
        640x480, scale (1, 1), K in COLMAP's convention (occgt's + 0.5 in cx, cy): the
        matches of occgt.pair_ground_truth with occgt's K, bit for bit; given as
        k_convention="occgt", other matches."""
        plain = make_batch(self.frames[:2])
        n = 2
        plain["image0"] = plain["image1"] = torch.zeros(n, 1, 480, 640)
        plain["scale0"] = plain["scale1"] = torch.ones(n, 2)
        rs = [occgt.pair_ground_truth(
            plain["depth0"][b].numpy(), plain["depth1"][b].numpy(), plain["K0"][b].numpy(),
            plain["K1"][b].numpy(), np.eye(4),
            np.linalg.inv(plain["T_0to1"][b].numpy().astype(np.float64)), "occ2net")
            for b in range(n)]
        want = [(b, i, j) for b, r in enumerate(rs) for i, j in r["matches"].tolist()]
        self.assertGreater(len(want), 1000)
        batch = colmap_k(plain)
        for k_convention in (None, "colmap"):
            with self.subTest(k_convention=k_convention):
                out = loftr_supervision(batch, "occ2net", preset="occ2net",
                                        k_convention=k_convention)
                self.assertEqual(ids(out), want)
                self.assertTrue(np.array_equal(out["spv_xy"].numpy(),
                                               np.concatenate([r["match_xy"] for r in rs])))
                self.assertTrue(np.array_equal(out["spv_cells0"].numpy(),
                                               np.stack([r["cells0"].ravel() for r in rs])))
        wrong = loftr_supervision(batch, "occ2net", preset="occ2net", k_convention="occgt")
        self.assertNotEqual(ids(wrong), want)
        # Without scale0/mask0 (not LoFTR's MegaDepth loader) K is occgt's unless told.
        for key in ("scale0", "scale1"):
            del plain[key], batch[key]
        self.assertEqual(ids(loftr_supervision(plain, "occ2net", preset="occ2net")), want)
        self.assertEqual(ids(loftr_supervision(batch, "occ2net", preset="occ2net",
                                               k_convention="colmap")), want)
        with self.assertRaisesRegex(ValueError, r"^k_convention: expected 'occgt', 'colmap' or "
                                    r"None, got 'opencv'$"):
            loftr_supervision(batch, "occ2net", k_convention="opencv")
        with self.assertRaisesRegex(ValueError, r"^k_convention: not an option of mode 'loftr' "
                                    r"\(got 'colmap'\)$"):
            loftr_supervision(batch, k_convention="colmap")

    def test_occ2net_stored_matches_take_no_options(self) -> None:
        """Stored matches (a split's, PairIndexDataset's) were computed with their own
        options: a preset, a label option or k_convention given here is refused (it was
        ignored); a coarse_stride or anchor other than theirs is refused from match_xy."""
        samples, _ = stored_samples(self.frames[:3])
        batch = Collate("pad")(samples)
        plain = loftr_supervision(batch, "occ2net")
        self.assertTrue(torch.equal(
            loftr_supervision(batch, "occ2net", preset="default")["spv_xy"], plain["spv_xy"]))
        for kwargs in (dict(preset="occ2net"), dict(preset="nonsense"), dict(min_depth_m=-5),
                       dict(bogus=1), dict(k_convention="colmap"), dict(k_convention="occgt"),
                       dict(mutual=False, preset="superglue")):
            name = next(iter(kwargs)) if "preset" not in kwargs else "preset"
            for layout in ("pad", "concat"):
                with self.subTest(kwargs=kwargs, layout=layout):
                    with self.assertRaisesRegex(
                            ValueError, "^" + name + r": the batch's matches were computed with "
                            r"the split's options .* drop 'matches' from the batch"):
                        loftr_supervision(Collate(layout)(samples), "occ2net", **kwargs)
        # Without 'matches' the options apply.
        computed = {k: v for k, v in batch.items()
                    if k not in ("matches", "match_type", "match_xy", "match_mask")}
        self.assertNotEqual(
            ids(loftr_supervision(computed, "occ2net", preset="occ2net", min_depth_m=2.5)),
            ids(plain))
        # coarse_stride and anchor: each match_xy lies in its target cell by the split's.
        for kwargs, text in ((dict(coarse_stride=4), r"coarse_stride=4, anchor='center'"),
                             (dict(anchor="corner"), r"coarse_stride=8, anchor='corner'"),
                             (dict(coarse_stride=16), r"coarse_stride=16")):
            with self.subTest(kwargs=kwargs):
                with self.assertRaisesRegex(ValueError, r"^batch\['(match_xy|matches)'\]: row "
                                            r"\d+ .*" + text):
                    loftr_supervision(batch, "occ2net", **kwargs)
        corner, rs = stored_samples(self.frames[:3], stride=16, anchor="corner")
        out = loftr_supervision(Collate("concat")(corner), "occ2net", coarse_stride=16,
                                anchor="corner")
        self.assertTrue(np.array_equal(out["spv_xy"].numpy(),
                                       np.concatenate([r["match_xy"] for r in rs])))
        with self.assertRaisesRegex(ValueError, r"^batch\['match_xy'\]: row \d+ \((vv|vo|ov)\)"
                                    r" at .* is not in its target cell \d+ of image [01] with "
                                    r"coarse_stride=16, anchor='center'"):
            loftr_supervision(Collate("concat")(corner), "occ2net", coarse_stride=16)
        # A match_xy moved by a cell: refused; by 5e-4 px across a border: kept.
        moved = Collate("pad")(samples)
        moved["match_xy"] = moved["match_xy"].clone()
        moved["match_xy"][0, 0, 0] += 8.0
        with self.assertRaisesRegex(ValueError, r"^batch\['match_xy'\]: row 0 "):
            loftr_supervision(moved, "occ2net")
        border = Collate("pad")(samples)
        j = int(border["matches"][0, 0, 1])
        border["match_xy"] = border["match_xy"].clone()
        x = np.float32((j % 80) * 8 - 0.5 - 5e-4)  # center: cell c starts at 8c - 0.5
        self.assertEqual(np.floor((np.float64(x) + 0.5) / 8), j % 80 - 1)
        border["match_xy"][0, 0, 0] = float(x)
        loftr_supervision(border, "occ2net")

    def test_occ2net_mode(self) -> None:
        samples, results = stored_samples(self.frames[:3])
        want_b = np.concatenate([np.full(len(r["match_type"]), b) for b, r in enumerate(results)])
        want_m = np.concatenate([r["matches"] for r in results])
        want_t = np.concatenate([r["match_type"] for r in results])
        want_xy = np.concatenate([r["match_xy"] for r in results])
        self.assertGreater(int((want_t == occgt.VO).sum()), 10)
        self.assertGreater(int((want_t == occgt.OV).sum()), 10)
        for layout in ("pad", "concat"):
            with self.subTest(layout=layout):
                out = loftr_supervision(Collate(layout)(samples), "occ2net")
                self.check_occ2net(out, want_b, want_m, want_t, want_xy, anchor="center")
        # Computed here from depth/K/T (world_from_cam0 = I, world_from_cam1 = inv(T_0to1)).
        batch = Collate("pad")(samples)
        del batch["matches"], batch["match_type"], batch["match_xy"], batch["match_mask"]
        for preset, anchor in (("occ2net", "center"), ("default", "corner")):
            with self.subTest(preset=preset, anchor=anchor):
                out = loftr_supervision(batch, "occ2net", preset=preset, anchor=anchor,
                                        mutual=True)
                rs = [occgt.pair_ground_truth(
                    batch["depth0"][b].numpy(), batch["depth1"][b].numpy(),
                    batch["K0"][b].numpy(), batch["K1"][b].numpy(), np.eye(4),
                    np.linalg.inv(batch["T_0to1"][b].numpy().astype(np.float64)), preset,
                    anchor=anchor) for b in range(3)]
                self.check_occ2net(
                    out, np.concatenate([np.full(len(r["match_type"]), b)
                                         for b, r in enumerate(rs)]),
                    np.concatenate([r["matches"] for r in rs]),
                    np.concatenate([r["match_type"] for r in rs]),
                    np.concatenate([r["match_xy"] for r in rs]), anchor=anchor)
                self.assertTrue(np.array_equal(out["spv_cells0"].numpy(),
                                               np.stack([r["cells0"].ravel() for r in rs])))
                self.assertTrue(np.array_equal(out["spv_cells1"].numpy(),
                                               np.stack([r["cells1"].ravel() for r in rs])))
        with self.assertRaises(ValueError):
            loftr_supervision(batch, "occ2net", preset="nonsense")
        with self.assertRaises(ValueError):
            loftr_supervision(batch, "occ2net", compat=True)
        # mode "loftr" takes no preset or anchor (a value given was ignored).
        with self.assertRaisesRegex(ValueError, r"^preset: not an option of mode 'loftr' "
                                    r"\(got 'occ2net'\)$"):
            loftr_supervision(batch, "loftr", preset="occ2net")
        with self.assertRaisesRegex(ValueError, r"^anchor: not an option of mode 'loftr'"):
            loftr_supervision(batch, "loftr", anchor="corner")
        bad = Collate("pad")(samples)
        del bad["match_mask"]
        with self.assertRaises(ValueError):
            loftr_supervision(bad, "occ2net")
        # A damaged stored match: a cell outside the grid, a type outside 0..2.
        damaged = Collate("pad")(samples)
        damaged["matches"] = damaged["matches"].clone()
        damaged["matches"][0, 0, 0] = 10**6
        with self.assertRaisesRegex(ValueError, r"^batch\['matches'\]: row 0 names cell 1000000 "
                                    r"of image 0, which has \d+ cells with coarse_stride=8$"):
            loftr_supervision(damaged, "occ2net")
        damaged = Collate("pad")(samples)
        damaged["match_type"] = damaged["match_type"].clone()
        damaged["match_type"][0, 0] = 7
        with self.assertRaisesRegex(ValueError, r"^batch\['match_type'\]: expected 0"):
            loftr_supervision(damaged, "occ2net")

    def check_occ2net(self, out: Dict[str, torch.Tensor], b: np.ndarray, m: np.ndarray,
                      t: np.ndarray, xy: np.ndarray, anchor: str) -> None:
        self.assertTrue(np.array_equal(out["spv_b_ids"].numpy(), b))
        self.assertTrue(np.array_equal(out["spv_i_ids"].numpy(), m[:, 0]))
        self.assertTrue(np.array_equal(out["spv_j_ids"].numpy(), m[:, 1]))
        self.assertTrue(np.array_equal(out["spv_type"].numpy(), t))
        self.assertTrue(np.array_equal(out["spv_xy"].numpy(), xy))
        for name, code in (("spv_vv_ids", occgt.VV), ("spv_vo_ids", occgt.VO),
                           ("spv_ov_ids", occgt.OV)):
            self.assertTrue(np.array_equal(out[name].numpy(), np.nonzero(t == code)[0]))
        # The fine target: (xy − the target cell's anchor) / 2 / 2, anchor (8c + 4, 8r + 4)
        # or (8c, 8r), the target cell j in image 1 (vv, vo) or i in image 0 (ov).
        cell = np.where(t == occgt.OV, m[:, 0], m[:, 1])
        half = 4 if anchor == "center" else 0
        anchor_xy = np.stack([(cell % 80) * 8 + half, (cell // 80) * 8 + half], 1)
        want = (xy - anchor_xy.astype(np.float32)) / 4
        self.assertTrue(np.allclose(out["expec_f_gt"].numpy(), want, atol=1e-6))
        vv = t == occgt.VV
        if anchor == "center":  # x in [8c − 0.5, 8c + 7.5): target in [−1.125, 0.875)
            f = out["expec_f_gt"].numpy()[vv]
            self.assertTrue(bool(((f >= -1.125) & (f < 0.875)).all()))
        conf = out["conf_matrix_gt"]
        self.assertEqual(int(conf.sum()), len(set(zip(b.tolist(), m[:, 0].tolist(),
                                                      m[:, 1].tolist()))))
        self.assertTrue(bool((conf[torch.from_numpy(b), torch.from_numpy(m[:, 0]).long(),
                                   torch.from_numpy(m[:, 1]).long()] == 1).all()))


SPLIT_RECIPE = """name: supervision-{name}
split: supervision-{name}
seed: 0
resolution: [640, 480]
dataset: {{format: sevenscenes, root: {root}, frame_stride: 2, min_valid_depth_fraction: 0.3}}
labels: {{preset: default}}
patches: {{stride: {stride}, anchor: {anchor}, mutual: true}}
selection:
  max_frame_gap: 6
  pruning: {{max_distance_m: 2.0, max_view_angle_deg: 60, frustum: true}}
  score_stride: 8
  overlap: [0.4, 0.9]
  occlusion: [0.0, 1.0]
  aggregate: mean
  quota_per_scene: 12
occupancy: {{enabled: false}}
sample: {{image: none, depth: true, labels: false, occupancy: false}}
shards: {{samples_per_shard: 4}}
"""


class BuiltSplits(unittest.TestCase):
    def test_stored_matches_of_real_shards(self) -> None:
        """mode="occ2net" over ShardDataset batches of 7-Scenes splits built with
        (stride, anchor) = (8, center) and (16, corner): with the split's coarse_stride and
        anchor, the stored matches as they are (every match_xy in its target cell, which the
        stride check relies on); with the other split's, refused."""
        from torch.utils.data import DataLoader

        from occgt.torch import ShardDataset, collate

        work = common.scratch("supervision_splits")
        variants = [(8, "center"), (16, "corner")]
        splits = []
        for stride, anchor in variants:
            recipe = os.path.join(work, f"s{stride}.yaml")
            with open(recipe, "w") as f:
                f.write(SPLIT_RECIPE.format(name=f"s{stride}", root=common.shared("sevenscenes"),
                                            stride=stride, anchor=anchor))
            out = os.path.join(work, f"s{stride}")
            common.occgt("build", recipe, "--out", out)
            splits.append(ShardDataset(out, occupancy="none", images=False, labels=False))
        for k, (stride, anchor) in enumerate(variants):
            rows = 0
            for batch in DataLoader(splits[k], batch_size=4, collate_fn=collate):
                out = loftr_supervision(batch, "occ2net", coarse_stride=stride, anchor=anchor)
                mask = batch["match_mask"]
                self.assertTrue(torch.equal(out["spv_xy"], batch["match_xy"][mask]))
                self.assertTrue(torch.equal(out["spv_j_ids"], batch["matches"][mask][:, 1]))
                rows += int(mask.sum())
                other_stride, other_anchor = variants[1 - k]
                with self.assertRaisesRegex(ValueError, r"^batch\['(match_xy|matches)'\]: row "
                                            r"\d+ .*coarse_stride=" + str(other_stride)):
                    loftr_supervision(batch, "occ2net", coarse_stride=other_stride,
                                      anchor=other_anchor)
                with self.assertRaisesRegex(ValueError, "anchor=" + repr(other_anchor)):
                    loftr_supervision(batch, "occ2net", coarse_stride=stride,
                                      anchor=other_anchor)
            self.assertGreater(rows, 2000, (stride, anchor))


class TartanAir(unittest.TestCase, Checks):
    def test_every_pair(self) -> None:
        ds = occgt.open_dataset(common.shared("tartanair/hospital_sample"), "tartanair")
        scene = ds.scene(ds.scenes()[0])
        ids_ = [f.id for f in scene.frames]
        pairs = [(ids_[k], ids_[k + g]) for k, g in ((0, 3), (2, 8), (5, 12), (10, 13), (1, 22))]
        total = {"matches": 0, "out_of_grid": 0}
        for k, frames in enumerate(scene_pairs(scene, pairs)):
            c = self.check_batch(make_batch([frames]), f"TartanAir {pairs[k]}")
            total["matches"] += c["matches"]
            total["out_of_grid"] += c["out_of_grid"]
        self.assertGreater(total["matches"], 3000)
        self.assertGreater(total["out_of_grid"], 100)


class Synthetic(unittest.TestCase, Checks):
    def test_every_pair(self) -> None:
        # 32 frames of an orbit: neighbours overlap; far frames look away (behind points).
        root = common.synth_dataset("synth_supervision", frames=32, resolution="320x240")
        scene = occgt.open_dataset(root, "generic").scene("synth_000")
        ids_ = [f.id for f in scene.frames]
        pairs = [(ids_[a], ids_[b]) for a, b in ((0, 1), (0, 2), (5, 6), (10, 12), (20, 21),
                                                 (30, 31), (3, 5), (0, 8))]
        frames = scene_pairs(scene, pairs, 320, 240)
        total = {"matches": 0, "behind": 0}
        for k, f in enumerate(frames):
            c = self.check_batch(make_batch([f]), f"synthetic {pairs[k]}")
            total["matches"] += c["matches"]
            total["behind"] += c["behind"]
        self.assertGreater(total["matches"], 3000)
        self.assertGreater(total["behind"], 100)
        self.check_batch(make_batch(frames), "synthetic batch")


if __name__ == "__main__":
    unittest.main()
