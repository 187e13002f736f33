"""JSON lines that people may write (pair and tuple lists), parsed strictly."""
from __future__ import annotations

import json
from typing import Any, Dict, List, Tuple


def _object(pairs: List[Tuple[str, Any]]) -> Dict[str, Any]:
    out: Dict[str, Any] = {}
    for key, value in pairs:
        if key in out:
            raise ValueError(f"duplicate key {key!r} (a key may appear once in an object)")
        out[key] = value
    return out


def loads_strict(text: str) -> Any:
    """``json.loads``, but an object that gives a key twice is a ValueError.

    ``json.loads`` keeps the last value of a repeated key; an edited line with ``"scene"``
    twice would silently use the second (the C++ readers refuse it the same way).
    """
    return json.loads(text, object_pairs_hook=_object)
