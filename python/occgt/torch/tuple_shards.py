"""TupleShardDataset: map-style random access into the N-view shards of ``occgt tuples
--shards`` (``DIR/views``), with the items of TupleIndexDataset read instead of computed.

The shards are listed once by the C++ shard reader, as for ShardDataset (shards.py); a
sample's members are read with one ``os.preadv``. The stored ground truth (``visible_in``,
``occluded_in``, ``valid``, the tracks) is the one ``occgt tuples --shards`` computed; only
``seen_by`` is derived, by the C++ that checks each item against its json
(``shards::CheckViewsSampleValues``, the rules ``occgt validate`` applies, with the count of
``occgt.views_seen_by``). docs/MULTIVIEW.md.
"""
from __future__ import annotations

import json
import os
from typing import Any, Dict, List, Tuple, Union

import numpy as np

from occgt import _occgt

from .shards import _decode, _has, _ShardSplit
from .tuples import _tuple_item

__all__ = ["TupleShardDataset"]

# The members every N-view sample holds (docs/FORMATS.md "N-view shards"); the images and
# depth<i> per view are checked when an item is read (the json gives the number of views).
_NEED = ("json", "intrinsics.npy", "world_from_cam.npy", "visible_in.npy", "occluded_in.npy",
         "valid.npy", "queries.npy", "track_xy.npy", "track_depth.npy", "track_state.npy",
         "depth0.npy")


def _whole(field: str, value: Any, low: int, high: int) -> int:
    """value, an integer in low..high (not a bool, float or string), of the json's field."""
    if type(value) is not int or not low <= value <= high:
        raise ValueError(f"{field}: expected an integer {low}..{high}, got {value!r:.40}")
    return value


def _fields(meta_bytes: bytes, key: str) -> Tuple[int, int, int, str, int,
                                                  List[Tuple[str, int]]]:
    """num_views, W, H, scene, tuple_index and frames [(id, number)] of a sample's json
    member, checked against views_sample.schema.json and the sample's key (ValueError)."""
    meta = json.loads(meta_bytes)
    if not isinstance(meta, dict):
        raise ValueError(f"expected an object, got {type(meta).__name__}")
    missing = [f for f in ("key", "scene", "tuple_index", "num_views", "frames", "resolution")
               if f not in meta]
    if missing:
        raise ValueError(f"no {', '.join(missing)}")
    if meta["key"] != key:
        raise ValueError(f"key {meta['key']!r:.60}, expected the sample's {key!r}")
    n = _whole("num_views", meta["num_views"], 1, 32)
    index = _whole("tuple_index", meta["tuple_index"], 0, 2**63 - 1)
    scene, frames, size = meta["scene"], meta["frames"], meta["resolution"]
    if not isinstance(scene, str) or not scene:
        raise ValueError(f"scene: expected a non-empty string, got {scene!r:.40}")
    if not isinstance(size, list) or len(size) != 2:
        raise ValueError(f"resolution: expected [W, H], got {size!r:.40}")
    W, H = (_whole("resolution", v, 1, 2**31 - 1) for v in size)
    if (not isinstance(frames, list) or len(frames) != n or
            not all(isinstance(f, dict) and isinstance(f.get("id"), str) and
                    type(f.get("number")) is int for f in frames)):
        raise ValueError(f"frames: expected num_views ({n}) objects {{id: string, number: "
                         f"integer}}, got {frames!r:.60}")
    return n, W, H, scene, index, [(f["id"], f["number"]) for f in frames]


class TupleShardDataset(_ShardSplit):
    """Map-style dataset over the N-view shards of ``occgt tuples --shards``.

    Args:
        split_dir: the N-view split folder, ``DIR/views`` of ``occgt tuples RECIPE --out DIR
            --shards`` (``index.json``, the ``.tar`` shards, ``pairs.jsonl``).
        images: read each view's ``image<i>.png`` / ``.jpg`` (``images``); a split written
            with ``sample.image: none`` has none (ValueError at construction).
        views: ``"vggt"`` (default) or ``"dust3r"``, as TupleIndexDataset.
        dataset_name: the ``dataset`` value of ``"dust3r"`` views (shards do not record the
            dataset's format; TupleIndexDataset puts its ``format`` there).

    Item i is sample i in shard order (the split's ``pairs.jsonl`` order, i.e. tuples.jsonl's
    order): the keys, dtypes and shapes of TupleIndexDataset's items, and the same values as
    ``TupleIndexDataset(DIR/tuples.jsonl, root, format, width=W, height=H, preset=...,
    num_tracks=..., query_view=..., seed=<the recipe's seed>, dataset_max_depth_m=...)[i]``
    (the recipe's ``selection.tuples`` num_tracks and query_view, its ``dataset.min_depth_m``
    / ``max_depth_m`` as ``dataset_min_depth_m`` / ``dataset_max_depth_m`` when set, its label
    overrides; tests/python/tuple_shards_test.py), with ``tuple_id`` = the sample's
    ``tuple_index``. The tracks are those of the json's ``tracks.query_view`` (the recipe's
    ``selection.tuples.query_view``, 0 by default: the first view, as VGGT's).

    Raises:
        ValueError: as ShardDataset's, naming the file: a missing or malformed
            ``index.json`` (and where the N-view shards are when given ``DIR``), a missing or
            damaged shard, a pair sample of ``occgt build`` (read by ShardDataset), a sample
            lacking a member, a member of another dtype or shape than its json's
            ``num_views`` and ``resolution`` say, a json field of another type or value
            than views_sample.schema.json's or a ``key`` other than the sample's; and, as
            ``<shard>: <key>.<member>: <problem>``, arrays that disagree with the json or
            with each other (C++ ``shards::CheckViewsSampleValues``, the rules of ``occgt
            validate``, docs/CLI.md): a json pose that is not rigid or K that is not a
            pinhole's, ``intrinsics`` / ``world_from_cam`` other than the json's, a depth
            that is negative or not finite, ``valid`` other than the depth's mask, a bit for
            a view the tuple does not have, a pixel both VISIBLE and OCCLUDED in a view, a
            bit where ``valid`` is 0, a diagonal bit that is not ``valid``, bit counts other
            than the json's ``metrics``, queries other than the sampling rule's, a track
            state other than 0..4 or other than the bits at its query pixel, a track without
            a position where its state is VISIBLE, OCCLUDED or INCONSISTENT.
    """

    def __init__(self, split_dir: Union[str, "os.PathLike[str]"], *, images: bool = True,
                 views: str = "vggt", dataset_name: str = "occgt") -> None:
        if views not in ("vggt", "dust3r"):
            raise ValueError(f"views: expected 'vggt' or 'dust3r', got {views!r}")
        if not isinstance(images, (bool, np.bool_)):
            raise TypeError(f"images: expected a bool, got {type(images).__name__}")
        if not isinstance(dataset_name, str):
            raise TypeError(f"dataset_name: expected a str, got {type(dataset_name).__name__}")
        self.images = bool(images)
        self.views = views
        self.dataset_name = dataset_name
        folder = os.fspath(split_dir)
        if (not os.path.exists(os.path.join(folder, "index.json")) and
                os.path.exists(os.path.join(folder, "views", "index.json"))):
            raise ValueError(f"{os.path.join(folder, 'index.json')}: missing; the N-view shards "
                             f"of occgt tuples --shards are in {os.path.join(folder, 'views')}")
        super().__init__(folder)
        for i, sample in enumerate(self._samples):
            where = f"{self._paths[sample.shard]}: sample {self._keys[i]}"
            if not _has(sample.members, "visible_in.npy") and _has(sample.members,
                                                                   "label01.npy"):
                raise ValueError(f"{where} is a pair sample of occgt build (read by "
                                 f"ShardDataset); TupleShardDataset reads the N-view samples "
                                 f"of occgt tuples --shards")
            for m in _NEED:
                if not _has(sample.members, m):
                    raise ValueError(f"{where} has no {m} member (every N-view sample has it)")
            if self.images and not ("image0.png" in sample.members or
                                    "image0.jpg" in sample.members):
                raise ValueError(f"{where} has no image0.png or image0.jpg member (asked for "
                                 f"by images=True; the recipe's sample.image was none?)")

    def __getitem__(self, i: int) -> Any:
        j, buf, members, where, meta_bytes = self._read(i)
        try:
            n, W, H, scene, index, frames = _fields(meta_bytes, self._keys[j])
        except ValueError as e:  # JSONDecodeError, UnicodeDecodeError too
            raise ValueError(f"{where}.json: expected the N-view sample fields of "
                             f"schemas/views_sample.schema.json: {e}") from None
        size_text = f"{n} views of {W}x{H}"

        def array(field: str, dtype: str, shape: Tuple[Any, ...]) -> np.ndarray:
            return self._array(buf, members, field, where, dtype, shape, size_text)

        for v in range(n):
            if not _has(members, f"depth{v}.npy"):
                raise ValueError(f"{where}: no depth{v}.npy member ({size_text})")
        depths = np.stack([array(f"depth{v}.npy", "f4", (H, W)) for v in range(n)])
        Ks = array("intrinsics.npy", "f8", (n, 3, 3))
        poses = array("world_from_cam.npy", "f8", (n, 4, 4))
        truth: Dict[str, Any] = {
            "visible_in": array("visible_in.npy", "u4", (n, H, W)),
            "occluded_in": array("occluded_in.npy", "u4", (n, H, W)),
            "valid": array("valid.npy", "u1", (n, H, W)),
        }
        truth["track_xy"] = array("track_xy.npy", "f4", (n, None, 2))
        q = truth["track_xy"].shape[1]
        truth["track_state"] = array("track_state.npy", "u1", (n, q))
        # The json and every array against each other, in C++ (shards::CheckViewsSampleValues,
        # as occgt validate: cameras, depth and valid, bits, metrics, queries, tracks), with
        # the C++ count of seen_by; ValueError "<where>.<field>: <problem>".
        checked = {f"depth{v}.npy": depths[v] for v in range(n)}
        checked.update({"intrinsics.npy": Ks, "world_from_cam.npy": poses,
                        "queries.npy": array("queries.npy", "i4", (q, 2)),
                        "track_depth.npy": array("track_depth.npy", "f4", (n, q))})
        checked.update({f"{k}.npy": truth[k] for k in ("visible_in", "occluded_in", "valid",
                                                       "track_xy", "track_state")})
        truth["seen_by"] = _occgt.check_views_sample(meta_bytes.decode("utf-8", "replace"),
                                                     checked, where)
        colors = None
        if self.images:
            rgb = []
            for v in range(n):
                field = f"image{v}.png" if f"image{v}.png" in members else f"image{v}.jpg"
                if field not in members:
                    raise ValueError(f"{where}: no image{v}.png or image{v}.jpg member "
                                     f"({size_text}; images=True)")
                offset, size = members[field]
                data = np.frombuffer(buf, dtype=np.uint8, count=size, offset=offset)
                rgb.append(_decode(data, f"{where}.{field}", H, W)[:, :, ::-1].transpose(2, 0, 1))
            colors = np.ascontiguousarray(np.stack(rgb))
        return _tuple_item(self.views, depths=depths, Ks=Ks, world_from_cams=poses,
                           truth=truth, colors=colors, scene=scene,
                           frame_ids=tuple(f for f, _ in frames),
                           numbers=[number for _, number in frames], index=index,
                           dataset=self.dataset_name)
