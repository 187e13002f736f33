"""NumPy values of a sample -> torch values, and the item index check (shared by the
datasets of occgt.torch)."""
from __future__ import annotations

import operator
from typing import Any

import numpy as np
import torch


def to_tensor(value: Any) -> Any:
    """A NumPy array becomes a tensor sharing its memory; other values are returned as they are.

    torch has no uint64, uint32 or uint16: uint64 and uint32 words are reinterpreted as int64
    and int32 (the same bits; ``(w >> k) & 1`` tests bit k on the signed view too), uint16 is
    widened to int32. A read-only or non-contiguous array (a memory map, a view) is copied,
    since torch warns on read-only memory.
    """
    if not isinstance(value, np.ndarray):
        return value
    if value.dtype.byteorder not in ("=", "|"):
        value = value.astype(value.dtype.newbyteorder("="))
    if value.dtype == np.uint64:
        value = value.view(np.int64)
    elif value.dtype == np.uint32:
        value = value.view(np.int32)
    elif value.dtype == np.uint16:
        value = value.astype(np.int32)
    if not value.flags.writeable or not value.flags.c_contiguous:
        value = np.ascontiguousarray(value).copy()
    return torch.from_numpy(value)


def item_index(index: Any, count: int, noun: str, name: str = "index") -> int:
    """``index`` as an int in 0..count - 1, a negative one counting from the end (as a list
    index); else TypeError / IndexError naming ``name`` ("index 9 out of range for 4 pairs").
    A bool is not an int here (as everywhere in occgt: ``ds[True]`` is a mistake, not item 1)."""
    if isinstance(index, bool):
        raise TypeError(f"{name}: expected an int, got bool")
    try:
        i = operator.index(index)  # an int, a numpy or 0-d torch integer; not 1.5 or "1"
    except TypeError:
        raise TypeError(f"{name}: expected an int, got {type(index).__name__}") from None
    if not -count <= i < count:
        raise IndexError(f"{name} {i} out of range for {count} {noun}")
    return i % count
