"""LoFTR's coarse supervision, and Occ²Net's vv/vo/ov supervision, over a collated batch.

``loftr_supervision(batch)`` is a drop-in for LoFTR's ``compute_supervision_coarse`` (its
``spvs_coarse``) plus the fine target of ``spvs_fine`` at the ground-truth matches; the
per-pair numerics are occgt's C++ (``occgt._occgt.loftr_coarse_supervision``, libgt/truth/
loftr_supervision.h; ``occgt.pair_ground_truth`` for ``mode="occ2net"``). Docs:
docs/PYTHON.md, "Supervision".
"""
from __future__ import annotations

from typing import Any, Dict, List, Literal, Mapping, Optional, Tuple, Union

import numpy as np
import torch

from .. import _occgt
from .. import pair_ground_truth

Mode = Literal["loftr", "occ2net"]
#: The pixel convention of a batch's K0/K1 (mode "occ2net"): occgt's (pixel centre at
#: integer coordinates) or COLMAP's (at +0.5: LoFTR's MegaDepth loader, occgt's MegaDepth
#: export).
KConvention = Literal["occgt", "colmap"]

#: Codes of spv_status0/spv_status1 (uint8): WARP_STATUS_NAMES[code] is the name.
WARP_STATUS_NAMES: Tuple[str, ...] = tuple(_occgt.WARP_STATUS_NAMES)
IN_GRID, NO_DEPTH, BEHIND, OUT_OF_GRID, PADDED = 0, 1, 2, 3, 4
# spv_cells0/1 of mode "occ2net" on a padded image's cells (LABEL_NAMES has codes 0..5).
PADDED_CELL = 255


def _numpy(t: Any, name: str) -> np.ndarray:
    if isinstance(t, torch.Tensor):
        return t.detach().cpu().numpy()
    if isinstance(t, np.ndarray):
        return t
    raise ValueError(f"batch[{name!r}]: expected a tensor, got {type(t).__name__}")


def _require(batch: Mapping[str, Any], keys: List[str], mode: str) -> None:
    for k in keys:
        if k not in batch:
            raise ValueError(f"batch: mode {mode!r} needs the key {k!r} (the sample contract "
                             f"of occgt.torch), got keys {sorted(batch.keys())}")


def _batched(batch: Mapping[str, Any], key: str, shape: Tuple[int, ...]) -> np.ndarray:
    """batch[key] as NumPy [N, *shape] (shape entries < 0: any size)."""
    a = _numpy(batch[key], key)
    ok = a.ndim == len(shape) + 1 and all(s < 0 or a.shape[i + 1] == s for i, s in enumerate(shape))
    if not ok:
        want = ", ".join(["N"] + [str(s) if s >= 0 else "?" for s in shape])
        raise ValueError(f"batch[{key!r}]: expected shape [{want}] (a collated batch), "
                         f"got {list(a.shape)}")
    return a


def _scales(batch: Mapping[str, Any], n: int) -> Tuple[np.ndarray, np.ndarray]:
    """LoFTR's data['scale0'] / ['scale1'] [N, 2] (present only together, as LoFTR tests
    'scale0' for both), else ones."""
    if "scale0" not in batch:
        return np.ones((n, 2), np.float32), np.ones((n, 2), np.float32)
    _require(batch, ["scale1"], "loftr")
    s0 = _batched(batch, "scale0", (2,)).astype(np.float32)
    s1 = _batched(batch, "scale1", (2,)).astype(np.float32)
    return s0, s1


def _image_size(batch: Mapping[str, Any], k: int, depth: np.ndarray) -> Tuple[int, int]:
    """(H, W) of image k: of batch['image<k>'] [N, 1, H, W] (LoFTR's H0, W0), else of the
    depth maps."""
    key = f"image{k}"
    if key in batch:
        shape = tuple(batch[key].shape)
        if len(shape) != 4:
            raise ValueError(f"batch[{key!r}]: expected shape [N, 1, H, W], got {list(shape)}")
        return int(shape[2]), int(shape[3])
    return int(depth.shape[1]), int(depth.shape[2])


def _conf_matrix(n: int, l0: int, l1: int, b: torch.Tensor, i: torch.Tensor, j: torch.Tensor,
                 dense: bool, unique: bool) -> torch.Tensor:
    """1 at every (b, i, j). Dense: NumPy's zeros (calloc: the kernel's zero pages, so only
    the pages holding a match are written here; LoFTR's torch.zeros writes all N·L0·L1
    floats). Sparse: COO; ``unique`` = the ids are sorted and distinct (no coalesce pass)."""
    if dense:
        conf = torch.from_numpy(np.zeros((n, l0, l1), np.float32))
        conf[b, i, j] = 1.0
        return conf
    idx = torch.stack([b, i, j]) if b.numel() else torch.zeros((3, 0), dtype=torch.int64)
    coo = torch.sparse_coo_tensor(idx, torch.ones(idx.shape[1]), (n, l0, l1))
    return coo._coalesced_(True) if unique else coo.coalesce()


def loftr_supervision(
    batch: Mapping[str, Any],
    mode: Mode = "loftr",
    *,
    coarse_stride: int = _occgt.SUPERVISION_DEFAULTS["coarse_stride"],
    fine_stride: int = 2,
    fine_window: int = 5,
    compat: bool = _occgt.SUPERVISION_DEFAULTS["compat"],
    dense_conf_matrix: bool = True,
    preset: str = _occgt.PAIR_DEFAULTS["preset"],
    anchor: str = _occgt.PAIR_DEFAULTS["anchor"],
    k_convention: Optional[KConvention] = None,
    **label_options: Any,
) -> Dict[str, torch.Tensor]:
    """Coarse and fine supervision of a collated batch (docs/PYTHON.md, "Supervision").

    Use it where LoFTR calls ``compute_supervision_coarse``: ``batch.update(
    loftr_supervision(batch))``. The batch holds the keys of the sample contract
    (occgt.torch) stacked on dim 0: ``depth0``, ``depth1`` [N, H, W] planar metres (0 =
    none), ``K0``, ``K1`` [N, 3, 3] at the depth maps' size, ``T_0to1`` (cam1_from_cam0)
    [N, 4, 4] and, when present, ``T_1to0``, ``image0``/``image1`` [N, 1, H, W] (their size
    sets the grid), LoFTR's ``scale0``/``scale1`` [N, 2] (depth-map pixels per image pixel)
    and ``mask0``/``mask1`` [N, h_c, w_c] (LoFTR's padded MegaDepth images: the coarse
    grid's mask, 0 on the padding). Work is on the CPU, one pair at a time without the GIL; the outputs are on the device
    of ``depth0``.

    mode="loftr": LoFTR's ``spvs_coarse`` (corner grid points (c, r)·8·scale, both-way
    warps of the depth at the nearest pixel, division by z + 1e-4, the nearest cell, the
    mutual loop-back, no depth-consistency test), except three fixes: a grid point without
    depth, one behind the other camera and one whose cell is outside the other grid give no
    match (LoFTR sends them to a corner or to cell 0), and cell 0 is an ordinary cell; with
    ``mask0``/``mask1``, a padded cell has no target (status ``padded``, warp NaN) and a
    target on the other image's padding is out of the grid (LoFTR moves padded grid points
    to (0, 0) and warps them). ``compat=True`` gives LoFTR exactly (also its dummy match (0, 0, 0) for a batch without
    any). Keys: ``conf_matrix_gt`` float32 [N, L0, L1] (1 at every match; a sparse COO
    tensor with ``dense_conf_matrix=False``), ``spv_b_ids``, ``spv_i_ids``, ``spv_j_ids``
    int64 [M] (by pair, then by i), ``spv_w_pt0_i`` float32 [N, L0, 2] (image 0's grid
    warped into image 1, its pixels; NaN without depth or behind camera 1), ``spv_pt1_i``
    [N, L1, 2] (image 1's grid), ``expec_f_gt`` [M, 2] = (w_pt0_i[b, i] − pt1_i[b, j]) /
    (fine_stride · scale1[b]) / (fine_window // 2) at these matches (LoFTR's ``spvs_fine``
    computes it at the coarse matcher's ids: loftr_fine_target gives it there), and
    occgt's ``spv_w_pt1_i``, ``spv_pt0_i`` and ``spv_status0``/``spv_status1`` uint8
    [N, L] (WARP_STATUS_NAMES: in_grid, no_depth, behind, out_of_grid, padded).

    mode="occ2net": occgt's vv, vo and ov patch matches (docs/GROUND_TRUTH.md §4): those of
    the batch (``matches``/``match_type``/``match_xy``, padded with ``match_mask`` or
    concatenated with ``match_b_ids``, occgt.torch.collate) when present, else computed per
    pair with occgt.pair_ground_truth(depth0, depth1, K0, K1, I, inverse(T_0to1), preset,
    stride=coarse_stride, anchor=anchor, **label_options). Keys: ``spv_b_ids``,
    ``spv_i_ids``, ``spv_j_ids``, ``spv_type`` int64 [M] (0 vv, 1 vo, 2 ov), ``spv_xy``
    float32 [M, 2] (match_xy: the warped anchor, in image 1 for vv/vo, in image 0 for ov),
    ``expec_f_gt`` [M, 2] = (spv_xy − the anchor of the target cell, j in image 1 for vv/vo,
    i in image 0 for ov) / fine_stride / (fine_window // 2) (``anchor`` and ``coarse_stride``
    must be those the matches were computed with), ``spv_vv_ids``, ``spv_vo_ids``,
    ``spv_ov_ids`` int64 (rows of each type), ``conf_matrix_gt`` (1 at every match of any
    type) and, when computed here, ``spv_cells0``/``spv_cells1`` uint8 [N, L] (each cell's
    anchor label, LABEL_NAMES; PADDED_CELL = 255 on padding). LoFTR's resized and padded
    images (``scale0``/``scale1``, ``mask0``/``mask1``, MegaDepth): the ground truth is
    computed at each image's unpadded size (``image0``/``image1`` give the size, the mask's
    top-left block of ones the unpadded part) from the depth map's top-left
    round(w·sx) × round(h·sy) pixels resampled to it with K (occgt.depth_at_image_size,
    pixel-centre rules), and its cells are placed on the padded grid; matches stored in the
    batch are refused there (they are at the depth maps' size). ``k_convention``: the pixel
    convention of K0/K1, "occgt" (pixel centre at integer coordinates) or "colmap" (at
    +0.5; its cx, cy are taken 0.5 lower); None = "colmap" for a batch with ``scale0`` or
    ``mask0`` (only LoFTR's MegaDepth loader gives those keys, with COLMAP's K), else
    "occgt".

    Stored matches were computed with the options of the split (or PairIndexDataset) that
    made them: a non-default ``preset``, any ``label_options`` or a ``k_convention`` is
    then refused (drop ``matches`` from the batch to compute them here), and every match_xy
    must lie in its target cell by ``coarse_stride`` and ``anchor`` (occgt's target-cell
    rule), so a wrong ``coarse_stride`` is refused; a wrong ``anchor`` is refused only where
    a match lies where the two anchors' rules differ: pass the split's (recipe.json
    ``patches.anchor``).

    Raises:
        ValueError: a missing key or a tensor of the wrong shape, a bad option, ``mask0``
            without ``mask1``, a mask that is not a top-left block, or the C++ checks
            (naming them).
    """
    if mode not in ("loftr", "occ2net"):
        raise ValueError(f"mode: expected 'loftr' or 'occ2net', got {mode!r}")
    for name, v in (("coarse_stride", coarse_stride), ("fine_stride", fine_stride),
                    ("fine_window", fine_window)):
        if not isinstance(v, int) or v < 1:
            raise ValueError(f"{name}: expected an integer >= 1, got {v!r}")
    if fine_window < 3:
        raise ValueError(f"fine_window: expected >= 3 (radius fine_window // 2 >= 1), got "
                         f"{fine_window}")
    if ("mask0" in batch) != ("mask1" in batch):
        raise ValueError("batch: 'mask0' and 'mask1' (LoFTR's padded MegaDepth images) come "
                         "together, got only " + ("'mask0'" if "mask0" in batch else "'mask1'"))
    _require(batch, ["depth0", "depth1", "K0", "K1", "T_0to1"], mode)
    device: Union[torch.device, str] = (batch["depth0"].device
                                        if isinstance(batch["depth0"], torch.Tensor) else "cpu")
    if k_convention not in (None, "occgt", "colmap"):
        raise ValueError(f"k_convention: expected 'occgt', 'colmap' or None, got "
                         f"{k_convention!r}")
    if mode == "loftr":
        if label_options:
            raise ValueError(f"{sorted(label_options)[0]}: not an option of mode 'loftr'")
        # LoFTR's targets take no label preset, anchor or K convention (they use K as LoFTR
        # does): a value given would be ignored.
        for name, value in (("preset", preset), ("anchor", anchor)):
            if value != _occgt.PAIR_DEFAULTS[name]:
                raise ValueError(f"{name}: not an option of mode 'loftr' (got {value!r})")
        if k_convention is not None:
            raise ValueError(f"k_convention: not an option of mode 'loftr' (got "
                             f"{k_convention!r})")
        out = _loftr(batch, coarse_stride, fine_stride, fine_window, compat, dense_conf_matrix)
    else:
        if compat:
            raise ValueError("compat: an option of mode 'loftr' (use preset='occ2net-compat')")
        if "matches" in batch:
            _refuse_label_options(preset, k_convention, label_options)
        elif k_convention is None:
            k_convention = "colmap" if "scale0" in batch or "mask0" in batch else "occgt"
        out = _occ2net(batch, coarse_stride, fine_stride, fine_window, dense_conf_matrix, preset,
                       anchor, k_convention == "colmap", label_options)
    return {k: v.to(device) for k, v in out.items()}


def _loftr(batch: Mapping[str, Any], stride: int, fine_stride: int, fine_window: int,
           compat: bool, dense: bool) -> Dict[str, torch.Tensor]:
    depth0 = _batched(batch, "depth0", (-1, -1))
    depth1 = _batched(batch, "depth1", (-1, -1))
    n = depth0.shape[0]
    K0 = _batched(batch, "K0", (3, 3))
    K1 = _batched(batch, "K1", (3, 3))
    T01 = _batched(batch, "T_0to1", (4, 4))
    T10 = _batched(batch, "T_1to0", (4, 4)) if "T_1to0" in batch else None
    for key, a in (("depth1", depth1), ("K0", K0), ("K1", K1), ("T_0to1", T01), ("T_1to0", T10)):
        if a is not None and a.shape[0] != n:
            raise ValueError(f"batch[{key!r}]: expected {n} pairs (as depth0), got {a.shape[0]}")
    scale0, scale1 = _scales(batch, n)
    size0 = _image_size(batch, 0, depth0)
    size1 = _image_size(batch, 1, depth1)
    masks: Tuple[Optional[np.ndarray], Optional[np.ndarray]] = (None, None)
    if "mask0" in batch:
        masks = (_batched(batch, "mask0", (size0[0] // stride, size0[1] // stride)),
                 _batched(batch, "mask1", (size1[0] // stride, size1[1] // stride)))
        for key, a in (("mask0", masks[0]), ("mask1", masks[1])):
            if a.shape[0] != n:
                raise ValueError(f"batch[{key!r}]: expected {n} pairs (as depth0), got "
                                 f"{a.shape[0]}")
    per_pair = []
    for b in range(n):
        per_pair.append(_occgt.loftr_coarse_supervision(
            depth0[b], depth1[b], K0[b], K1[b], T01[b], None if T10 is None else T10[b],
            coarse_stride=stride, scale0=(float(scale0[b][0]), float(scale0[b][1])),
            scale1=(float(scale1[b][0]), float(scale1[b][1])), image_size0=size0,
            image_size1=size1,
            compat=compat,
            mask0=None if masks[0] is None else masks[0][b],
            mask1=None if masks[1] is None else masks[1][b]))
    stack = lambda key: torch.from_numpy(np.stack([p[key] for p in per_pair]))  # noqa: E731
    w_pt0_i, pt1_i = stack("warped0"), stack("grid1")
    l0, l1 = w_pt0_i.shape[1], pt1_i.shape[1]
    b_ids = torch.cat([torch.full((p["matches"].shape[0],), b, dtype=torch.int64)
                       for b, p in enumerate(per_pair)])
    ij = torch.from_numpy(np.concatenate([p["matches"] for p in per_pair])).to(torch.int64)
    i_ids, j_ids = ij[:, 0].contiguous(), ij[:, 1].contiguous()
    conf = _conf_matrix(n, l0, l1, b_ids, i_ids, j_ids, dense, unique=True)
    if compat and b_ids.numel() == 0:  # LoFTR's dummy match; conf_matrix_gt stays zero
        b_ids = i_ids = j_ids = torch.zeros(1, dtype=torch.int64)
    expec_f_gt = loftr_fine_target({"spv_w_pt0_i": w_pt0_i, "spv_pt1_i": pt1_i}, b_ids, i_ids,
                                   j_ids, fine_stride=fine_stride, fine_window=fine_window,
                                   scale1=torch.from_numpy(scale1))
    return {
        "conf_matrix_gt": conf,
        "spv_b_ids": b_ids,
        "spv_i_ids": i_ids,
        "spv_j_ids": j_ids,
        "spv_w_pt0_i": w_pt0_i,
        "spv_pt1_i": pt1_i,
        "expec_f_gt": expec_f_gt,
        "spv_w_pt1_i": stack("warped1"),
        "spv_pt0_i": stack("grid0"),
        "spv_status0": stack("status0"),
        "spv_status1": stack("status1"),
    }


def loftr_fine_target(spv: Mapping[str, torch.Tensor], b_ids: torch.Tensor, i_ids: torch.Tensor,
                      j_ids: torch.Tensor, *, fine_stride: int = 2, fine_window: int = 5,
                      scale1: Optional[torch.Tensor] = None) -> torch.Tensor:
    """LoFTR's ``spvs_fine`` at any coarse ids (the coarse matcher's ``b_ids``, ``i_ids``,
    ``j_ids``): (spv_w_pt0_i[b, i] − spv_pt1_i[b, j]) / (fine_stride · scale1[b]) /
    (fine_window // 2), float32 [M, 2]. ``spv``: the output of loftr_supervision (mode
    "loftr"); ``scale1``: the batch's [N, 2] (LoFTR's data['scale1']) or None. Rows at cells
    without depth or behind the camera are NaN, which LoFTR's fine loss drops (its
    ``norm(expec_f_gt, inf) < correct_thr`` is false for NaN)."""
    w_pt0_i, pt1_i = spv["spv_w_pt0_i"], spv["spv_pt1_i"]
    scale = float(fine_stride) if scale1 is None else fine_stride * scale1.to(w_pt0_i)[b_ids]
    return (w_pt0_i[b_ids, i_ids] - pt1_i[b_ids, j_ids]) / scale / (fine_window // 2)


def _batch_matches(batch: Mapping[str, Any], n: int) -> Tuple[torch.Tensor, ...]:
    """(b_ids, matches [M, 2], match_type [M], match_xy [M, 2]) of a batch's ground truth."""
    _require(batch, ["match_type", "match_xy"], "occ2net")
    matches = torch.as_tensor(batch["matches"])
    types = torch.as_tensor(batch["match_type"])
    xy = torch.as_tensor(batch["match_xy"])
    if "match_mask" in batch:
        mask = torch.as_tensor(batch["match_mask"]).bool()
        if matches.dim() != 3 or mask.shape != matches.shape[:2] or mask.shape[0] != n:
            raise ValueError(f"batch['matches']: expected [N, M, 2] with match_mask [N, M] "
                             f"(N = {n}), got {list(matches.shape)} and {list(mask.shape)}")
        b_ids = torch.nonzero(mask)[:, 0]
        return b_ids, matches[mask], types[mask], xy[mask]
    if "match_b_ids" in batch:
        b_ids = torch.as_tensor(batch["match_b_ids"]).to(torch.int64)
        if matches.dim() != 2 or b_ids.shape[0] != matches.shape[0]:
            raise ValueError(f"batch['matches']: expected [ΣM, 2] with match_b_ids [ΣM], got "
                             f"{list(matches.shape)} and {list(b_ids.shape)}")
        return b_ids, matches, types, xy
    raise ValueError("batch['matches']: expected match_mask (padded) or match_b_ids "
                     "(concatenated) with it (occgt.torch.collate)")


def _refuse_label_options(preset: str, k_convention: Optional[str],
                          label_options: Dict[str, Any]) -> None:
    """Stored matches take none of the options that compute matches: a value given would be
    ignored."""
    given = sorted(label_options.items())
    if k_convention is not None:
        given.insert(0, ("k_convention", k_convention))
    if preset != _occgt.PAIR_DEFAULTS["preset"]:
        given.insert(0, ("preset", preset))
    if given:
        name, value = given[0]
        raise ValueError(f"{name}: the batch's matches were computed with the split's options "
                         f"(recipe.json; PairIndexDataset: its own), got {value!r}; drop "
                         f"'matches' from the batch to compute them with other options")


def _check_target_cells(xy: torch.Tensor, cell: torch.Tensor, types: torch.Tensor,
                        grids: Tuple[Tuple[int, int], Tuple[int, int]], stride: int,
                        anchor: str) -> None:
    """Every stored match_xy lies in its target cell (j in image 1 for vv/vo, i in image 0 for
    ov; grids: (rows, cols) of images 0 and 1) by the C++ rule (_occgt.target_cells), within
    1e-3 px of it on each axis (the point or one of its four diagonal neighbours at 1e-3 px
    falls there), so matches of another coarse_stride are refused."""
    ov = (types == 2).detach().cpu().numpy()
    points = xy.detach().cpu().numpy().astype(np.float32)
    want = cell.detach().cpu().numpy()
    inside = np.zeros(len(points), bool)
    tol = 1e-3
    for dx, dy in ((0.0, 0.0), (-tol, -tol), (-tol, tol), (tol, -tol), (tol, tol)):
        moved = points + np.array([dx, dy], np.float32)
        for image, rows in ((0, ov), (1, ~ov)):
            h, w = grids[image]
            got = _occgt.target_cells(moved[rows].reshape(-1, 2), w, h, stride, anchor)
            inside[rows] |= got == want[rows]
    if bool(inside.all()):
        return
    k = int(np.nonzero(~inside)[0][0])
    kind = ("vv", "vo", "ov")[int(types[k])]
    image = 0 if kind == "ov" else 1
    raise ValueError(f"batch['match_xy']: row {k} ({kind}) at ({float(xy[k, 0]):.3f}, "
                     f"{float(xy[k, 1]):.3f}) is not in its target cell {int(cell[k])} of image "
                     f"{image} with coarse_stride={stride}, anchor={anchor!r}: the batch's "
                     f"matches were computed with another coarse_stride or anchor (pass the "
                     f"split's, recipe.json patches.stride and patches.anchor)")


def _valid_cells(mask: np.ndarray, key: str) -> Tuple[int, int]:
    """(rows, cols) of the unpadded top-left block of a LoFTR coarse mask [h_c, w_c]."""
    m = mask != 0
    rows, cols = int(m.any(1).sum()), int(m.any(0).sum())
    if rows == 0 or int(m.sum()) != rows * cols or not m[:rows, :cols].all():
        raise ValueError(f"batch[{key!r}]: expected the image's cells as a top-left block of "
                         f"ones (LoFTR pads at the bottom and right), got {int(m.sum())} ones "
                         f"over {rows} rows and {cols} columns")
    return rows, cols


def _occ2net(batch: Mapping[str, Any], stride: int, fine_stride: int, fine_window: int,
             dense: bool, preset: str, anchor: str, colmap_k: bool,
             label_options: Dict[str, Any]) -> Dict[str, torch.Tensor]:
    if anchor not in ("center", "corner"):
        raise ValueError(f"anchor: expected 'center' or 'corner', got {anchor!r}")
    depth0 = _batched(batch, "depth0", (-1, -1))
    depth1 = _batched(batch, "depth1", (-1, -1))
    n = depth0.shape[0]
    # Resized (scale0/1) or padded (mask0/1) images: the ground truth is computed at the
    # image's unpadded size (depth and K resampled to it) and its cells placed on the
    # padded grid of the image.
    resized = "scale0" in batch or "mask0" in batch
    if resized and "matches" in batch:
        raise ValueError("batch: 'matches' with 'scale0'/'mask0': stored matches are at the "
                         "depth maps' size; drop them to compute matches at the images' size")
    if resized:
        size0, size1 = _image_size(batch, 0, depth0), _image_size(batch, 1, depth1)
        if "image0" not in batch or "image1" not in batch:
            raise ValueError("batch: 'scale0'/'mask0' need 'image0' and 'image1' (their size "
                             "sets the grid)")
    else:
        size0, size1 = (depth0.shape[1], depth0.shape[2]), (depth1.shape[1], depth1.shape[2])
    grid0, grid1 = (size0[0] // stride, size0[1] // stride), (size1[0] // stride, size1[1] // stride)
    w0, w1 = grid0[1], grid1[1]
    l0, l1 = grid0[0] * w0, grid1[0] * w1
    out: Dict[str, torch.Tensor] = {}
    stored = "matches" in batch
    if stored:
        b_ids, matches, types, xy = _batch_matches(batch, n)
    else:
        K0 = _batched(batch, "K0", (3, 3))
        K1 = _batched(batch, "K1", (3, 3))
        if colmap_k:  # COLMAP's pixel centres are at +0.5, occgt's at integers
            K0, K1 = K0.astype(np.float64), K1.astype(np.float64)
            K0[:, :2, 2] -= 0.5
            K1[:, :2, 2] -= 0.5
        T01 = _batched(batch, "T_0to1", (4, 4)).astype(np.float64)
        scale0, scale1 = _scales(batch, n)
        masks = None
        if "mask0" in batch:
            masks = (_batched(batch, "mask0", grid0), _batched(batch, "mask1", grid1))
        eye = np.eye(4)
        results, valid_w = [], []
        for b in range(n):
            d0, k0, d1, k1 = depth0[b], K0[b], depth1[b], K1[b]
            if resized:
                # The unpadded block of each image, in pixels (whole cells with a mask).
                hw = []
                for k, (size, grid) in enumerate(((size0, grid0), (size1, grid1))):
                    if masks is None:
                        hw.append(size)
                    else:
                        rows, cols = _valid_cells(masks[k][b], f"mask{k}")
                        hw.append((rows * stride, cols * stride))
                s0 = (float(scale0[b][0]), float(scale0[b][1]))
                s1 = (float(scale1[b][0]), float(scale1[b][1]))
                d0, k0 = _occgt.depth_at_image_size(d0, k0, s0, hw[0][1], hw[0][0])
                d1, k1 = _occgt.depth_at_image_size(d1, k1, s1, hw[1][1], hw[1][0])
            valid_w.append((d0.shape[1] // stride, d1.shape[1] // stride))
            results.append(pair_ground_truth(d0, d1, k0, k1, eye, np.linalg.inv(T01[b]), preset,
                                             stride=stride, anchor=anchor, **label_options))
        b_ids = torch.cat([torch.full((r["matches"].shape[0],), b, dtype=torch.int64)
                           for b, r in enumerate(results)])
        # Cell c of the unpadded grid (vw columns) is cell (c // vw) * w + c % vw of the
        # image's grid (w columns); the same cell when nothing is padded.
        placed = []
        for r, (vw0, vw1) in zip(results, valid_w):
            m = r["matches"].astype(np.int64)
            placed.append(np.stack([(m[:, 0] // vw0) * w0 + m[:, 0] % vw0,
                                    (m[:, 1] // vw1) * w1 + m[:, 1] % vw1], 1))
        matches = torch.from_numpy(np.concatenate(placed).reshape(-1, 2))
        types = torch.from_numpy(np.concatenate([r["match_type"] for r in results]))
        xy = torch.from_numpy(np.concatenate([r["match_xy"] for r in results]))

        def cells(per_pair: List[np.ndarray], grid: Tuple[int, int]) -> torch.Tensor:
            full = np.full((n,) + grid, PADDED_CELL, np.uint8)
            for b, c in enumerate(per_pair):
                full[b, :c.shape[0], :c.shape[1]] = c
            return torch.from_numpy(full.reshape(n, -1))

        out["spv_cells0"] = cells([r["cells0"] for r in results], grid0)
        out["spv_cells1"] = cells([r["cells1"] for r in results], grid1)
    b_ids = b_ids.to(torch.int64)
    i_ids = matches[:, 0].to(torch.int64).contiguous()
    j_ids = matches[:, 1].to(torch.int64).contiguous()
    types = types.to(torch.int64)
    # A batch's stored matches name cells of the grids and the three types (a damaged cell
    # index reached the index arithmetic below).
    for name, ids, count in (("image 0", i_ids, l0), ("image 1", j_ids, l1)):
        outside = (ids < 0) | (ids >= count)
        if bool(outside.any()):
            k = int(torch.nonzero(outside)[0, 0])
            raise ValueError(f"batch['matches']: row {k} names cell {int(ids[k])} of {name}, "
                             f"which has {count} cells with coarse_stride={stride}")
    if bool(((types < 0) | (types > 2)).any()):
        raise ValueError("batch['match_type']: expected 0 (vv), 1 (vo) or 2 (ov)")
    xy = xy.to(torch.float32)
    # The anchor pixel of a cell (geometry/patches.h AnchorPixel): the target cell is j in
    # image 1 for vv/vo and i in image 0 for ov.
    half = stride // 2 if anchor == "center" else 0
    ov = types == 2
    cell = torch.where(ov, i_ids, j_ids)
    width = torch.where(ov, torch.tensor(w0), torch.tensor(w1))
    if stored:
        _check_target_cells(xy, cell, types, (grid0, grid1), stride, anchor)
    anchor_xy = torch.stack([(cell % width) * stride + half, (cell // width) * stride + half], 1)
    expec_f_gt = (xy - anchor_xy.to(torch.float32)) / fine_stride / (fine_window // 2)
    out.update({
        "conf_matrix_gt": _conf_matrix(n, l0, l1, b_ids, i_ids, j_ids, dense,
                                       unique=False),
        "spv_b_ids": b_ids,
        "spv_i_ids": i_ids,
        "spv_j_ids": j_ids,
        "spv_type": types,
        "spv_xy": xy,
        "expec_f_gt": expec_f_gt,
        "spv_vv_ids": torch.nonzero(types == 0)[:, 0],
        "spv_vo_ids": torch.nonzero(types == 1)[:, 0],
        "spv_ov_ids": torch.nonzero(ov)[:, 0],
    })
    return out


__all__ = ["WARP_STATUS_NAMES", "IN_GRID", "NO_DEPTH", "BEHIND", "OUT_OF_GRID", "PADDED", "PADDED_CELL",
           "loftr_fine_target", "loftr_supervision"]
