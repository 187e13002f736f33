"""NumPy values of a sample -> torch values (shared by the datasets of occgt.torch)."""
from __future__ import annotations

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
