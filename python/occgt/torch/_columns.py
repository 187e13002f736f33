"""What the indices held as NumPy columns (``PairIndex``, ``TupleIndex``) share.

An index of millions of entries held as one Python object per entry takes hundreds of bytes
an entry, and a forked DataLoader worker copies every page whose reference counts it touches.
Held as read-only NumPy columns (one entry a row; names, such as scenes, stored once and
referred to by int32 indices) it takes a few bytes an entry, and forked workers share it.
Entry i is made when asked; a slice is an index of the same class.
"""
from __future__ import annotations

from typing import Any, Dict, Iterator, List, Self, Sequence, TypeVar, Union, overload

import numpy as np

from ._convert import item_index

R = TypeVar("R")


def int_column(values: Any) -> np.ndarray:
    """Integers >= 0 as int32 when they fit (4 bytes an entry, not 8), else int64 (a negative
    one too: a column's int64 minimum is "not given")."""
    values = np.asarray(values, dtype=np.int64)
    if values.size and int(values.min()) >= 0 and int(values.max()) < 2**31:
        return values.astype(np.int32)
    return values


class SceneColumns(Sequence[R]):
    """Entries of an index as NumPy columns, in the index's order, each in a scene: ``scenes``
    (the scene names, each once, in order of first appearance) and ``scene`` (int32, one entry
    a row: index into ``scenes``). A subclass adds its columns, makes entry k (``_item``) and
    slices (``_slice``); every ndarray attribute is made read-only, again after unpickling."""

    #: The entries' name in messages ("index 9 out of range for 4 pairs").
    _noun = "entries"

    def __init__(self, scenes: Sequence[str], scene: np.ndarray) -> None:
        self.scenes: List[str] = list(scenes)
        self.scene = np.asarray(scene, dtype=np.int32)

    def _freeze(self) -> None:
        for value in vars(self).values():
            if isinstance(value, np.ndarray):
                value.flags.writeable = False

    def __setstate__(self, state: Dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._freeze()  # pickle gives writeable arrays back

    def _item(self, k: int) -> R:
        raise NotImplementedError

    def _slice(self, i: slice) -> Self:
        raise NotImplementedError

    def __len__(self) -> int:
        return len(self.scene)

    @overload
    def __getitem__(self, i: int) -> R: ...

    @overload
    def __getitem__(self, i: slice) -> Self: ...

    def __getitem__(self, i: Union[int, slice]) -> Union[R, Self]:
        if isinstance(i, slice):
            return self._slice(i)
        return self._item(item_index(i, len(self), self._noun))

    def __iter__(self) -> Iterator[R]:
        return (self._item(k) for k in range(len(self)))

    def __repr__(self) -> str:
        return f"{type(self).__name__}({len(self)} {self._noun} in {len(self.scenes)} scenes)"
