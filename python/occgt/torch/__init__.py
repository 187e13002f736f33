"""occgt.torch: torch Datasets, a collate function and LoFTR / Occ²Net supervision over occgt.

Pure Python over the C++ module (``occgt._occgt``); torch is Debian's ``python3-torch``.
Docs: docs/PYTHON.md, "ShardDataset", "PairIndexDataset" and "Supervision"; docs/MULTIVIEW.md
for TupleIndexDataset.

A sample (a dict) has the same keys whichever dataset yields it:

- LoFTR's keys (its ScanNet dataset's names, dtypes and layouts): ``image0``, ``image1``
  float32 [1, H, W] grey in [0, 1] (when the images exist); ``depth0``, ``depth1`` float32
  [H, W] planar metres, 0 = invalid; ``K0``, ``K1`` float32 [3, 3] at H×W; ``T_0to1``
  (= cam1_from_cam0), ``T_1to0`` float32 [4, 4]; ``dataset_name``, ``scene_id`` str,
  ``pair_id`` int, ``pair_names`` (str, str).
- occgt's ground truth, named as the ``.npy`` members of a shard without the extension:
  ``label01``, ``label10`` uint8 [H, W]; ``cells0``, ``cells1`` uint8 [H/s, W/s];
  ``matches`` int64 [M, 2]; ``match_type`` int64 [M]; ``match_xy`` float32 [M, 2];
  ``occ0``, ``known0``, ``occ1``, ``known1`` int64 [H/2, W/2] (the uint64 words' bits,
  reinterpreted: torch has no uint64) or, on request, ``occupancy0``, ``occupancy1`` uint8
  [D, H/2, W/2] (0 free, 1 occupied, 255 unknown); ``metrics01``, ``metrics10`` dicts.
- The grey images are the library's colour at the working resolution (a shard's
  ``image0.png``; of a split of ``sample.image: jpg``, its ``image0.jpg`` as OpenCV decodes
  it) converted with ``cv2.COLOR_RGB2GRAY``, divided by 255; ``pair_names`` are
  ``("<scene>/<frame id>", "<scene>/<frame id>")``.
- On request, ``color0``, ``color1`` uint8 [3, H, W] RGB (``ShardDataset(color=True)``).

N-view tuples (``TupleIndexDataset`` computes them, ``TupleShardDataset`` reads them from the
shards of ``occgt tuples --shards``; docs/MULTIVIEW.md) have their own keys: VGGT's
(``images``, ``depths``, ``extrinsics``, ``intrinsics``, ``point_masks``, ``tracks``,
``track_vis_mask``) and occgt's (``visible_in``, ``occluded_in``, ``track_state``,
``seen_by``); ``collate_tuples`` batches tuples of different sizes.
"""
from __future__ import annotations

from ._convert import to_tensor
from .collate import VARIABLE_KEYS, Collate, collate
from .pairs import PairIndex, PairIndexDataset, PairRef, read_pair_index
from .shards import ShardDataset
from .supervision import loftr_supervision
from .tuple_shards import TupleShardDataset
from .tuples import (TRACK_STATE_PADDED, TupleIndex, TupleIndexDataset, TupleRef, collate_tuples,
                     read_tuples)

__all__ = [
    "TRACK_STATE_PADDED",
    "VARIABLE_KEYS",
    "Collate",
    "PairIndex",
    "PairIndexDataset",
    "PairRef",
    "ShardDataset",
    "TupleIndex",
    "TupleIndexDataset",
    "TupleShardDataset",
    "TupleRef",
    "collate_tuples",
    "read_tuples",
    "collate",
    "loftr_supervision",
    "read_pair_index",
    "to_tensor",
]
