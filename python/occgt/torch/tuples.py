"""TupleIndexDataset: N-view samples with dense visibility, computed on the fly from a tuple
index (``occgt tuples``' tuples.jsonl, or lists of frame ids) and the dataset on disk.

Each ``__getitem__`` reads the tuple's frames with occgt's readers at the working resolution
and computes ``occgt.views_ground_truth`` (C++, GIL released) in the DataLoader worker.
Items carry VGGT's sample keys and occgt's; ``views="dust3r"`` gives DUSt3R's list of view
dicts instead. ``collate_tuples`` batches tuples of different sizes. docs/MULTIVIEW.md,
docs/PYTHON.md.
"""
from __future__ import annotations

import array
import dataclasses
import operator
import os
from typing import Any, Dict, Iterable, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import torch

import occgt

from .._occgt import check_resolution, views_options
from ._columns import SceneColumns, int_column
from ._convert import item_index, to_tensor
from ._json import loads_strict


@dataclasses.dataclass(frozen=True)
class TupleRef:
    """One tuple: the scene and its frame ids (the first is the reference / query view)."""

    scene: str
    frame_ids: Tuple[str, ...]


def _checked(scene: Any, frame_ids: Any) -> Tuple[str, Tuple[str, ...]]:
    """A tuple's scene name and frame ids, all str (a str is not a list of ids: "000001" would
    be six frames); ValueError saying what is wrong."""
    if not isinstance(scene, str) or not scene:
        raise ValueError(f"scene: expected a non-empty str, got {scene!r}")
    if isinstance(frame_ids, (str, bytes, dict)) or not hasattr(frame_ids, "__iter__"):
        raise ValueError(f"frame_ids: expected a list of str, got {type(frame_ids).__name__}")
    ids = tuple(frame_ids)
    bad = [i for i in ids if not isinstance(i, str)]
    if bad:
        raise ValueError(f"frame_ids: expected a list of str, got {bad[0]!r}")
    if len(set(ids)) != len(ids):  # schemas/tuples_line.schema.json: uniqueItems
        repeated = [i for n, i in enumerate(ids) if i in ids[:n]]
        raise ValueError(f"frame_ids: expected distinct frame ids, {repeated[0]!r} repeats")
    if not 2 <= len(ids) <= 32:  # schemas/tuples_line.schema.json: 2..32 views
        raise ValueError(f"frame_ids: expected 2..32 frame ids, got {len(ids)}")
    return str(scene), tuple(map(str, ids))


TupleLike = Union[TupleRef, Tuple[str, Sequence[str]]]


class TupleIndex(SceneColumns[TupleRef]):
    """The tuples of an index as NumPy columns, in the index's order; item i is a TupleRef,
    made when asked (a slice is a TupleIndex; equal items compare equal).

    A million tuples of 8 views held as TupleRefs took about 940 bytes a tuple (the ids' str
    objects of each line, the tuple, the dataclass, a ``"<path>:<line>"`` string) and a
    forked DataLoader worker copied the pages whose reference counts it touched; the columns
    take 48 bytes a tuple of 8 views and forked workers share them (PairIndex's layout,
    occgt/torch/_columns.py; docs/PERFORMANCE.md). Columns (read-only arrays):

    - ``scenes``: the scene names, each once, in order of first appearance; ``scene``: int32
      [N], index into ``scenes``;
    - ``frame_ids``: the frame ids, each once (ids such as ``"000150"`` recur across scenes);
      ``frame``: int32 indices into it, the tuples' views one tuple after the other;
      ``offsets``: int64 [N + 1], tuple k's views are ``frame[offsets[k]:offsets[k + 1]]``
      (``offsets[0]`` is 0, ``offsets[N]`` is ``len(frame)``); ``sizes``: the views of each
      tuple (``np.diff(offsets)``);
    - ``path`` and ``line``: the tuples.jsonl read and the line of each tuple (1-based, int32
      when it fits), or None for tuples given as a list (``from_refs``); ``where(k)``.
    """

    _noun = "tuples"

    def __init__(self, scenes: Sequence[str], scene: np.ndarray, frame_ids: Sequence[str],
                 frame: np.ndarray, offsets: np.ndarray, *,
                 path: Optional[str] = None, line: Optional[np.ndarray] = None) -> None:
        super().__init__(scenes, scene)
        self.frame_ids = list(frame_ids)
        self.frame = np.asarray(frame, dtype=np.int32)
        self.offsets = np.asarray(offsets, dtype=np.int64)
        self.path, self.line = path, line
        n = len(self.scene)
        if (len(self.offsets) != n + 1 or self.offsets[0] != 0
                or self.offsets[-1] != len(self.frame)):
            raise ValueError(f"TupleIndex.offsets: expected {n + 1} entries from 0 to "
                             f"len(frame) = {len(self.frame)}, got {len(self.offsets)}")
        if line is not None and len(line) != n:
            raise ValueError(f"TupleIndex.line: {len(line)} entries for {n} tuples")
        if (path is None) != (line is None):
            raise ValueError("TupleIndex: path and line go together")
        self._freeze()

    @classmethod
    def from_refs(cls, refs: Iterable[TupleLike]) -> "TupleIndex":
        """The columns of a sequence of TupleRef or (scene, [frame ids]): distinct str ids,
        2..32 of them (ValueError naming the first other item, ``tuples[k]``)."""
        columns = _Columns()
        for k, t in enumerate(refs):
            try:
                scene, ids = (t.scene, t.frame_ids) if isinstance(t, TupleRef) else t
                columns.add(*_checked(scene, ids))
            except (TypeError, ValueError) as e:
                raise ValueError(f"tuples[{k}]: expected a TupleRef or (scene, [frame ids]) "
                                 f"({type(e).__name__}: {e})") from None
        return columns.index()

    @property
    def sizes(self) -> np.ndarray:
        """int64 [N]: the number of views of each tuple."""
        return np.diff(self.offsets)

    def where(self, k: int) -> str:
        """Where tuple k comes from: ``"<path>:<line>"``, or ``"tuples[k]"`` (a list)."""
        if self.line is None:
            return f"tuples[{k}]"
        return f"{self.path}:{int(self.line[k])}"

    def _item(self, k: int) -> TupleRef:
        begin, end = self.offsets[k:k + 2].tolist()
        ids = self.frame_ids
        return TupleRef(self.scenes[int(self.scene[k])],
                        tuple([ids[j] for j in self.frame[begin:end].tolist()]))

    def _slice(self, i: slice) -> "TupleIndex":
        start, stop, step = i.indices(len(self))
        if step == 1:  # a view of the frame column; the offsets moved to start at 0
            offsets = self.offsets[start:max(start, stop) + 1]
            frame = self.frame[offsets[0]:offsets[-1]]
            offsets = offsets - offsets[0]
        else:
            rows = np.arange(start, stop, step)
            begin, sizes = self.offsets[rows], self.sizes[rows]
            offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
            frame = self.frame[np.repeat(begin - offsets[:-1], sizes) + np.arange(offsets[-1])]
        return TupleIndex(self.scenes, self.scene[i], self.frame_ids, frame, offsets,
                          path=self.path, line=None if self.line is None else self.line[i])


class _Columns:
    """A TupleIndex built tuple by tuple (compact arrays, names interned)."""

    def __init__(self) -> None:
        self.scenes: Dict[str, int] = {}
        self.frame_ids: Dict[str, int] = {}
        self.scene = array.array("i")
        self.frame = array.array("i")
        self.offsets = array.array("q", [0])

    def add(self, scene: str, frame_ids: Tuple[str, ...]) -> None:
        self.scene.append(self.scenes.setdefault(scene, len(self.scenes)))
        frames = self.frame_ids
        self.frame.extend([frames.setdefault(i, len(frames)) for i in frame_ids])
        self.offsets.append(len(self.frame))

    def index(self, path: Optional[str] = None,
              line: Optional["array.array[int]"] = None) -> TupleIndex:
        return TupleIndex(list(self.scenes), np.array(self.scene, dtype=np.int32),
                          list(self.frame_ids), np.array(self.frame, dtype=np.int32),
                          np.array(self.offsets, dtype=np.int64), path=path,
                          line=None if line is None else int_column(line))


def _read_tuple_lines(path: Union[str, os.PathLike]) -> TupleIndex:
    """read_tuples' tuples, with the line of each."""
    p = os.fspath(path)
    if os.path.isdir(p):
        inside = os.path.join(p, "tuples.jsonl")
        raise ValueError(f"{p}: a folder, expected a tuples.jsonl file"
                         + (f" (pass {inside}: the tuples of occgt tuples --out {p})"
                            if os.path.isfile(inside) else ""))
    columns, lines = _Columns(), array.array("q")
    with open(p, "rb") as f:
        for number, raw in enumerate(f, 1):
            try:
                line = raw.decode("utf-8")
                if not line.strip():
                    continue
                t = loads_strict(line)
                columns.add(*_checked(t["scene"], t["frame_ids"]))
                lines.append(number)
            except (ValueError, KeyError, TypeError) as e:
                raise ValueError(f"{p}:{number}: expected a tuple line with scene and frame_ids "
                                 f"({type(e).__name__}: {e})") from None
    return columns.index(f"{p}", lines)


def read_tuples(path: Union[str, os.PathLike]) -> TupleIndex:
    """The tuples of an ``occgt tuples`` tuples.jsonl (schemas/tuples_line.schema.json), in
    order, as a TupleIndex (NumPy columns; item i a TupleRef); ValueError naming the line of a
    bad one (scene a str, frame_ids a list of 2..32 distinct str), or saying so when ``path``
    is a folder (``occgt tuples``' DIR: pass DIR/tuples.jsonl)."""
    return _read_tuple_lines(path)


#: ``track_state`` of the views and tracks that ``collate_tuples`` pads (0 would read as
#: ``occgt.TRACK_VISIBLE``); not one of ``occgt.TRACK_STATE_NAMES``.
TRACK_STATE_PADDED = 255

#: Track seeds are uint64: item i's is (seed + i) mod 2^64, the sum `occgt tuples --shards`
#: computes (libgt/pipeline/views_write.cc, recipe.seed + uint64 index).
_SEEDS = 2**64


class TupleIndexDataset(torch.utils.data.Dataset):  # type: ignore[type-arg]
    """N-view samples of a tuple index, ground truth computed on the fly.

    Args:
        tuples: a tuples.jsonl path (not occgt tuples' DIR: ValueError), a list of
            ``TupleRef`` / ``(scene, [frame ids])`` (distinct frame ids), or a
            ``TupleIndex``; held as a TupleIndex (``tuples``). An item whose frame the scene
            lacks raises ValueError naming the tuple and its line (or list entry).
        root, format: the dataset (``occgt.open_dataset``).
        device: ScanNet++'s camera, ``"dslr"`` or ``"iphone"`` (``occgt.open_dataset``).
        tum_max_dt_s: TUM's association tolerance (``occgt.open_dataset``; None: the default,
            else a recipe's ``dataset.tum_max_dt_s``).
        depth_source, mesh_path, fused_depth: the depth of every view (``Scene.load``):
            ``"sensor"``, or ``"mesh"``/``"fused"`` with the scene's mesh (``mesh_path``,
            ``{scene}`` = the scene's name, as a recipe's ``dataset.mesh_path``; None: the
            reader's) and, for ``"fused"``, the tolerances ``fused_depth`` (a recipe's
            ``dataset.fused_depth``; None: the defaults).
        width, height: the working resolution of every view.
        preset, **label_options: the label options of ``occgt.views_ground_truth`` (the
            scene's depth range is passed as ``dataset_depth_range`` unless given; a recipe's
            ``dataset.min_depth_m`` / ``max_depth_m`` are ``dataset_min_depth_m`` /
            ``dataset_max_depth_m``, its label overrides keep their names).
        num_tracks: tracks sampled from view ``query_view``'s valid pixels (seed
            ``(seed + index) mod 2**64``, as ``occgt tuples --shards`` adds them, so an item
            is the same in every epoch and worker).
        query_view: the view of each tuple whose pixels are the tracks' queries (a recipe's
            ``selection.tuples.query_view``); below every tuple's size (ValueError here).
        images: read the colour images (``images``; a frame without colour raises ValueError);
            a bool (TypeError otherwise).
        views: ``"vggt"`` (default): one dict of stacked views; ``"dust3r"``: a list of view
            dicts.

    A ``"vggt"`` item (S views, P tracks): ``images`` float32 [S, 3, H, W] RGB in [0, 1];
    ``depths`` float32 [S, H, W] (0 = none); ``extrinsics`` float32 [S, 3, 4] camera-from-world
    (OpenCV); ``intrinsics`` float32 [S, 3, 3]; ``point_masks`` bool [S, H, W] (the view's own
    valid depth); ``tracks`` float32 [S, P, 2] (x, y) of view query_view's query pixels in each
    view (0 where they do not project); ``track_vis_mask`` bool [S, P] (VISIBLE);
    ``track_state`` uint8 [S, P] (``occgt.TRACK_STATE_NAMES``); ``visible_in``,
    ``occluded_in`` int32 [S, H, W] (the uint32 bitmasks' bits: bit j = VISIBLE / OCCLUDED
    in view j); ``seen_by`` uint8 [S, H, W]; ``ids`` int64 [S] (frame numbers);
    ``frame_ids``, ``scene_id``, ``tuple_id``.

    A ``"dust3r"`` item: a list of S dicts ``{img float32 [3, H, W] in [-1, 1] (DUSt3R's
    normalisation), depthmap, camera_pose float32 [4, 4] cam-to-world, camera_intrinsics,
    dataset, label (scene), instance (frame id), idx, true_shape, valid_mask, visible_in,
    occluded_in}``.
    """

    def __init__(self, tuples: Union[str, os.PathLike, TupleIndex, Sequence[TupleLike]],
                 root: str, format: str, *, width: int = occgt.PAIR_DEFAULTS["width"],
                 height: int = occgt.PAIR_DEFAULTS["height"],
                 preset: str = occgt.PAIR_DEFAULTS["preset"], num_tracks: int = occgt.VIEWS_DEFAULTS["num_tracks"],
                 seed: int = occgt.VIEWS_DEFAULTS["seed"],
                 query_view: int = occgt.VIEWS_DEFAULTS["query_view"], images: bool = True,
                 views: str = "vggt",
                 device: str = occgt.DATASET_DEFAULTS["device"],
                 tum_max_dt_s: Optional[float] = None,
                 depth_source: str = occgt.DATASET_DEFAULTS["depth_source"],
                 mesh_path: Optional[str] = None,
                 fused_depth: Optional[Dict[str, float]] = None, **label_options: Any) -> None:
        if views not in ("vggt", "dust3r"):
            raise ValueError(f"views: expected 'vggt' or 'dust3r', got {views!r}")
        self.tuples: TupleIndex = (read_tuples(tuples) if isinstance(tuples, (str, os.PathLike))
                                   else tuples if isinstance(tuples, TupleIndex)
                                   else TupleIndex.from_refs(tuples))
        if depth_source not in ("sensor", "mesh", "fused"):
            raise ValueError(f"depth_source: expected 'sensor', 'mesh' or 'fused', got {depth_source!r}")
        if not isinstance(images, (bool, np.bool_)):  # "no" is not a bool (it was truthy)
            raise TypeError(f"images: expected a bool, got {type(images).__name__}")
        # Fail here, not in a worker: the size, and the options as views_ground_truth resolves
        # them (a misspelt or unknown option, a bad preset or value, a negative seed).
        check_resolution(width, height)
        views_options(preset, num_tracks=num_tracks, query_view=query_view, seed=seed,
                      **label_options)
        self.query_view = operator.index(query_view)
        short = np.flatnonzero(self.tuples.sizes <= self.query_view)
        if short.size:
            k = int(short[0])
            t = self.tuples[k]
            raise ValueError(f"query_view: expected a view of every tuple, got "
                             f"{self.query_view}; tuples[{k}] has {len(t.frame_ids)} "
                             f"views ({t.scene}: {', '.join(t.frame_ids)})")
        self.root, self.format, self.device = root, format, device
        self.tum_max_dt_s = tum_max_dt_s
        self.depth_source, self.mesh_path, self.fused_depth = depth_source, mesh_path, fused_depth
        self.width, self.height = operator.index(width), operator.index(height)
        self.preset, self.num_tracks, self.seed = preset, operator.index(num_tracks), operator.index(seed)
        self.images, self.views = bool(images), views
        self.label_options = dict(label_options)
        self._dataset: Optional[occgt.Dataset] = None
        self._pid = -1
        # Per scene opened in this process: the scene and its frames' numbers by id.
        self._scenes: Dict[str, Tuple[occgt.Scene, Dict[str, int]]] = {}
        # Fail here, not in a worker, on a bad root, format or device (the readers open the
        # root lazily: test it here).
        occgt.open_dataset(root, format, device=device, tum_max_dt_s=tum_max_dt_s)
        if not os.path.exists(root):
            raise ValueError(f"root: {root}: no such dataset folder or file")

    def __getstate__(self) -> Dict[str, Any]:
        """The readers and maps of this process stay here (a spawned DataLoader worker or a
        pickle opens its own; the C++ objects cannot be pickled)."""
        state = self.__dict__.copy()
        state.update(_dataset=None, _scenes={}, _pid=-1)
        return state

    def __len__(self) -> int:
        return len(self.tuples)

    def _scene(self, name: str) -> Tuple[occgt.Scene, Dict[str, int]]:
        if self._pid != os.getpid():  # a forked worker opens its own readers
            self._dataset = occgt.open_dataset(self.root, self.format, device=self.device,
                                               tum_max_dt_s=self.tum_max_dt_s)
            self._scenes, self._pid = {}, os.getpid()
        if name not in self._scenes:
            assert self._dataset is not None
            scene = self._dataset.scene(name)
            if self.mesh_path is not None:  # "{scene}" = the scene's name, as in a recipe
                scene.mesh_path = self.mesh_path.replace("{scene}", name)
            self._scenes[name] = (scene, {f.id: f.number for f in scene.frames})
        return self._scenes[name]

    def __getitem__(self, index: int) -> Any:
        index = item_index(index, len(self.tuples), "tuples")
        ref = self.tuples[index]
        try:
            scene, numbers = self._scene(ref.scene)
        except ValueError as e:
            raise ValueError(f"tuple {index} ({self.tuples.where(index)}): {e}") from None
        unknown = [i for i in ref.frame_ids if i not in numbers]
        if unknown:
            raise ValueError(f"tuple {index} ({self.tuples.where(index)}): frame_ids: no frame "
                             f"with id {unknown[0]!r} in scene {ref.scene} under {self.root}")
        loaded = [scene.load(i, self.width, self.height, depth_source=self.depth_source,
                             fused_depth=self.fused_depth) for i in ref.frame_ids]
        depths = np.stack([d for d, _, _ in loaded])
        Ks = np.stack([K for _, K, _ in loaded])
        poses = np.stack([T for _, _, T in loaded])
        options: Dict[str, Any] = {"dataset_depth_range": (scene.min_depth_m, scene.max_depth_m),
                   **self.label_options}
        truth = occgt.views_ground_truth(
            depths, Ks, poses, preset=self.preset, num_tracks=self.num_tracks,
            query_view=self.query_view, seed=(self.seed + index) % _SEEDS, **options)
        colors = None
        if self.images:
            colors = np.stack([scene.load_color(i, self.width, self.height)
                               for i in ref.frame_ids]).transpose(0, 3, 1, 2)  # [S, 3, H, W]
        return _tuple_item(self.views, depths=depths, Ks=Ks, world_from_cams=poses,
                           truth=truth, colors=colors, scene=ref.scene,
                           frame_ids=ref.frame_ids,
                           numbers=[numbers[i] for i in ref.frame_ids], index=index,
                           dataset=self.format)


def _tuple_item(views: str, *, depths: np.ndarray, Ks: np.ndarray, world_from_cams: np.ndarray,
                truth: Mapping[str, Any], colors: Optional[np.ndarray], scene: str,
                frame_ids: Tuple[str, ...], numbers: Sequence[int], index: int,
                dataset: str) -> Any:
    """One item of TupleIndexDataset / TupleShardDataset (their docstrings) from the tuple's
    arrays: depths float32 [S, H, W], Ks [S, 3, 3], world_from_cams float64 [S, 4, 4], the
    N-view truth (``valid``, ``visible_in``, ``occluded_in``, ``seen_by``, ``track_xy``,
    ``track_state`` as views_ground_truth returns them), colors uint8 [S, 3, H, W] RGB or
    None, the frame ids and numbers, the tuple's index and the dataset's name."""
    height, width = depths.shape[1:]
    if views == "dust3r":
        out = []
        for s, frame_id in enumerate(frame_ids):
            view: Dict[str, Any] = {
                "depthmap": to_tensor(depths[s]),
                "camera_pose": to_tensor(world_from_cams[s].astype(np.float32)),
                "camera_intrinsics": to_tensor(Ks[s].astype(np.float32)),
                "dataset": dataset, "label": scene, "instance": frame_id,
                "idx": (index, s), "true_shape": np.array([height, width]),
                "valid_mask": to_tensor(truth["valid"][s].astype(bool)),
                "visible_in": to_tensor(truth["visible_in"][s]),
                "occluded_in": to_tensor(truth["occluded_in"][s]),
            }
            if colors is not None:
                view["img"] = to_tensor(colors[s].astype(np.float32) / 127.5 - 1.0)
            out.append(view)
        return out
    cam_from_world = np.linalg.inv(world_from_cams)[:, :3, :].astype(np.float32)
    xy = truth["track_xy"]
    sample: Dict[str, Any] = {
        "depths": to_tensor(depths),
        "extrinsics": to_tensor(cam_from_world),
        "intrinsics": to_tensor(Ks.astype(np.float32)),
        "point_masks": to_tensor(truth["valid"].astype(bool)),
        "tracks": to_tensor(np.where(np.isnan(xy), np.float32(0), xy)),
        "track_vis_mask": to_tensor(truth["track_state"] == occgt.TRACK_VISIBLE),
        "track_state": to_tensor(truth["track_state"]),
        "visible_in": to_tensor(truth["visible_in"]),
        "occluded_in": to_tensor(truth["occluded_in"]),
        "seen_by": to_tensor(truth["seen_by"]),
        "ids": to_tensor(np.array(numbers, np.int64)),
        "frame_ids": tuple(frame_ids), "scene_id": scene, "tuple_id": index,
    }
    if colors is not None:
        sample["images"] = to_tensor(colors.astype(np.float32) / 255.0)
    return sample


def collate_tuples(batch: Sequence[Dict[str, Any]]) -> Dict[str, Any]:
    """Batches "vggt" items of different sizes: tensors whose first axis is the view axis S
    (and, for tracks, the track axis P) are zero-padded to the largest in the batch and
    stacked; ``view_mask`` bool [B, S_max] marks real views, ``track_vis_mask`` stays False
    and ``track_state`` is ``TRACK_STATE_PADDED`` on the padding; other values become
    lists. Every item must have the keys and the view size (H, W) of the first (ValueError
    naming the item otherwise: nothing is dropped)."""
    if not batch:
        raise ValueError("batch: expected at least one item")
    keys = list(batch[0]) if isinstance(batch[0], dict) else []
    for n, item in enumerate(batch):
        if not isinstance(item, dict) or "depths" not in item or "tracks" not in item:
            raise ValueError(f"batch[{n}]: expected a 'vggt' item of TupleIndexDataset (a dict "
                             f"with depths, tracks, ...), got "
                             + (f"a dict of {sorted(item)}" if isinstance(item, dict)
                                else type(item).__name__)
                             + (" (views='dust3r' items are lists: batch them as DUSt3R does)"
                                if isinstance(item, list) else ""))
        if list(item) != keys:  # e.g. images=True and images=False items: nothing dropped
            raise ValueError(f"batch[{n}]: expected the keys of batch[0] {keys}, got "
                             f"{list(item)}")
        if item["depths"].shape[1:] != batch[0]["depths"].shape[1:]:
            raise ValueError(f"batch[{n}]: views of {tuple(item['depths'].shape[1:])} (H, W), "
                             f"expected batch[0]'s {tuple(batch[0]['depths'].shape[1:])}")
    s_max = max(int(b["depths"].shape[0]) for b in batch)
    p_max = max(int(b["tracks"].shape[1]) for b in batch)
    out: Dict[str, Any] = {}
    for key, value in batch[0].items():
        if not isinstance(value, torch.Tensor):
            out[key] = [b[key] for b in batch]
            continue
        padded = []
        for b in batch:
            t = b[key]
            shape = list(t.shape)
            shape[0] = s_max
            if key in ("tracks", "track_vis_mask", "track_state"):
                shape[1] = p_max
            z = (torch.full(shape, TRACK_STATE_PADDED, dtype=t.dtype) if key == "track_state"
                 else torch.zeros(shape, dtype=t.dtype))
            z[tuple(slice(0, n) for n in t.shape)] = t
            padded.append(z)
        out[key] = torch.stack(padded)
    out["view_mask"] = torch.stack([torch.arange(s_max) < int(b["depths"].shape[0])
                                    for b in batch])
    return out
