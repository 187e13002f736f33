"""Batches of occgt samples: variable-length matches padded with a mask, or concatenated.

A sample's ``matches`` [M, 2], ``match_type`` [M] and ``match_xy`` [M, 2] have a different M
for every pair, which torch's default collate cannot stack. ``Collate`` batches them in one of
two documented ways and leaves every other key to ``torch.utils.data.default_collate`` (LoFTR's
own collate), so LoFTR's keys come out as LoFTR's loader gives them.
"""
from __future__ import annotations

from typing import Any, Dict, List, Literal, Sequence

import torch
from torch.utils.data import default_collate

#: Keys whose first dimension differs between samples (one row per patch match).
VARIABLE_KEYS = ("matches", "match_type", "match_xy")

MatchBatching = Literal["pad", "concat"]


class Collate:
    """A ``collate_fn`` for ``torch.utils.data.DataLoader`` over occgt samples.

    ``matches="pad"`` (default): ``matches`` [B, M_max, 2], ``match_type`` [B, M_max],
    ``match_xy`` [B, M_max, 2], zero past each sample's M, and ``match_mask`` bool [B, M_max]
    (True for real rows). ``matches="concat"``: the rows of all samples one after the other,
    ``matches`` [ΣM, 2] etc., with ``match_b_ids`` int64 [ΣM] = the sample of each row (the
    layout of LoFTR's ``spv_b_ids``). Every other key: ``default_collate``.
    """

    def __init__(self, matches: MatchBatching = "pad") -> None:
        if matches not in ("pad", "concat"):
            raise ValueError(f"matches: expected 'pad' or 'concat', got {matches!r}")
        self.matches = matches

    def __call__(self, samples: Sequence[Dict[str, Any]]) -> Dict[str, Any]:
        if not samples:
            raise ValueError("samples: expected at least one sample")
        # The same keys in any order (ShardDataset and PairIndexDataset items in one
        # ConcatDataset); the batch has samples[0]'s order.
        keys = list(samples[0].keys())
        for i, s in enumerate(samples):
            if s.keys() != samples[0].keys():
                missing = [k for k in keys if k not in s]
                extra = [k for k in s if k not in samples[0]]
                raise ValueError(f"samples[{i}]: expected the keys of samples[0]; missing "
                                 f"{missing}, extra {extra}")
        batch: Dict[str, Any] = {}
        for key in keys:
            values = [s[key] for s in samples]
            if key in VARIABLE_KEYS:
                continue
            shapes = [tuple(v.shape) for v in values if isinstance(v, torch.Tensor)]
            if len(shapes) == len(values) and len(set(shapes)) > 1:
                i = next(k for k, shape in enumerate(shapes) if shape != shapes[0])
                raise ValueError(f"samples[{i}][{key!r}]: expected the shape of samples[0] "
                                 f"{list(shapes[0])}, got {list(shapes[i])} (samples of "
                                 f"other sizes: resize them to one size in the datasets)")
            batch[key] = default_collate(values)
        present = [k for k in VARIABLE_KEYS if k in keys]
        if present:
            rows = [int(s[present[0]].shape[0]) for s in samples]
            for key in present:
                values = [s[key] for s in samples]
                for i, v in enumerate(values):
                    if int(v.shape[0]) != rows[i]:
                        raise ValueError(f"samples[{i}][{key!r}]: expected {rows[i]} rows "
                                         f"(as {present[0]!r}), got {int(v.shape[0])}")
                batch[key] = _pad(values, max(rows)) if self.matches == "pad" else torch.cat(values)
            if self.matches == "pad":
                mask = torch.zeros(len(samples), max(rows), dtype=torch.bool)
                for i, m in enumerate(rows):
                    mask[i, :m] = True
                batch["match_mask"] = mask
            else:
                batch["match_b_ids"] = torch.repeat_interleave(
                    torch.arange(len(samples), dtype=torch.int64), torch.tensor(rows))
        return batch


def _pad(values: List[torch.Tensor], rows: int) -> torch.Tensor:
    first = values[0]
    out = torch.zeros((len(values), rows) + tuple(first.shape[1:]), dtype=first.dtype)
    for i, v in enumerate(values):
        out[i, : v.shape[0]] = v
    return out


#: ``Collate()`` (matches padded, with ``match_mask``).
collate = Collate()
