"""PairIndexDataset: ground truth computed on the fly from a pair index and the dataset on disk.

No shard is needed: each ``__getitem__`` reads the pair's two frames with occgt's readers (at
the working resolution) and computes occgt's ground truth with ``occgt.pair_ground_truth``
(the C++ library, GIL released), in the DataLoader worker. docs/PYTHON.md, "PairIndexDataset:
ground truth on the fly".
"""
from __future__ import annotations

import dataclasses
import json
import operator
import os
from typing import Any, Dict, Iterable, Iterator, List, Optional, Sequence, Tuple, Union

import cv2
import numpy as np
import torch

import occgt

from .._occgt import check_resolution
from ._columns import SceneColumns, int_column
from ._convert import item_index, to_tensor
from ._json import loads_strict

#: LoFTR's dataset_name for occgt's reader formats (its evaluation picks thresholds by it).
_DATASET_NAMES = {"scannet": "ScanNet", "megadepth": "MegaDepth"}


@dataclasses.dataclass(frozen=True)
class PairRef:
    """One pair of an index: the scene and both frames, by id or by number (LoFTR's indices
    name frames by number)."""

    scene: str
    frame0: Optional[str]
    frame1: Optional[str]
    number0: Optional[int] = None
    number1: Optional[int] = None
    score: Optional[float] = None


def _scene_names_file(npz_path: str) -> Optional[str]:
    """scenes.txt of occgt's LoFTR export: beside test.npz, or two folders above
    scene_data/{split}/<scene>.npz."""
    here = os.path.dirname(os.path.abspath(npz_path))
    for folder in (here, os.path.dirname(os.path.dirname(here))):
        path = os.path.join(folder, "scenes.txt")
        if os.path.isfile(path):
            return path
    return None


def _read_scene_names(path: str) -> List[str]:
    """Line i = scene i, as occgt's export writes scenes.txt: every line as it is but its line
    ending (a scene folder may begin with '#' or a space, or end with one)."""
    with open(path, encoding="utf-8", newline="\n") as f:  # only '\n' ends a line
        lines = f.read().split("\n")
    if lines[-1] == "":  # the last line's ending
        lines.pop()
    return [line[:-1] if line.endswith("\r") else line for line in lines]


def _read_lines(path: str) -> List[str]:
    with open(path) as f:
        return [line.strip() for line in f if line.strip() and not line.startswith("#")]


# A frame number the index does not give (a PairRef's None) in an int64 number column.
_NO_NUMBER = int(np.iinfo(np.int64).min)


class PairIndex(SceneColumns[PairRef]):
    """The pairs of an index as NumPy columns, in the index's order; item i is a PairRef, made
    when asked (a slice is a PairIndex).

    At the paper's scale (230 M pairs) a list of Python objects does not fit in memory (about
    430 bytes a PairRef) and a forked DataLoader worker copies it page by page as it touches
    reference counts; the columns take 16 to 20 bytes a pair for a LoFTR npz index (scene
    int32, two frame numbers int32 when they fit, the file's float score), 20 for pairs.jsonl
    (scene, two frame-id indices, two numbers; each frame id is stored once), and forked
    workers share them (occgt/torch/_columns.py). Columns (read-only arrays, one entry a pair):

    - ``scenes``: the scene names, each once, in order of first appearance; ``scene``: int32
      index into ``scenes`` (a sampler that takes pairs scene by scene groups on it);
    - ``frame_ids`` (a list of the frame ids, each once) with ``id0``/``id1`` int32 indices
      into it (-1: the pair names that frame by number), or None when no pair names a frame
      by id;
    - ``number0``/``number1``: frame numbers (int64 min: not given), or None when no pair
      gives numbers;
    - ``score``: the index's float scores (float64 for integer ones), NaN for a pair without
      one, or None when no pair has a score.
    """

    def __init__(self, scenes: Sequence[str], scene: np.ndarray, *,
                 frame_ids: Optional[Sequence[str]] = None, id0: Optional[np.ndarray] = None,
                 id1: Optional[np.ndarray] = None, number0: Optional[np.ndarray] = None,
                 number1: Optional[np.ndarray] = None,
                 score: Optional[np.ndarray] = None) -> None:
        super().__init__(scenes, scene)
        self.frame_ids = None if frame_ids is None else list(frame_ids)
        self.id0, self.id1 = id0, id1
        self.number0, self.number1, self.score = number0, number1, score
        n = len(self.scene)
        for name in ("id0", "id1", "number0", "number1", "score"):
            column = getattr(self, name)
            if column is not None and len(column) != n:
                raise ValueError(f"PairIndex.{name}: {len(column)} entries for {n} pairs")
        if (id0 is None) != (frame_ids is None) or (id0 is None) != (id1 is None):
            raise ValueError("PairIndex: frame_ids, id0 and id1 go together")
        if (number0 is None) != (number1 is None):
            raise ValueError("PairIndex: number0 and number1 go together")
        self._freeze()

    @classmethod
    def from_refs(cls, refs: Iterable[PairRef]) -> "PairIndex":
        """The columns of a sequence of PairRef (TypeError naming the first other item)."""
        scenes: Dict[str, int] = {}
        frames: Dict[str, int] = {}
        scene: List[int] = []
        id0: List[int] = []
        id1: List[int] = []
        number0: List[int] = []
        number1: List[int] = []
        score: List[float] = []
        for k, ref in enumerate(refs):
            if not isinstance(ref, PairRef):
                raise TypeError(f"pairs[{k}]: expected an occgt.torch.PairRef, got "
                                f"{type(ref).__name__}")
            scene.append(scenes.setdefault(ref.scene, len(scenes)))
            id0.append(-1 if ref.frame0 is None else frames.setdefault(ref.frame0, len(frames)))
            id1.append(-1 if ref.frame1 is None else frames.setdefault(ref.frame1, len(frames)))
            for out, number in ((number0, ref.number0), (number1, ref.number1)):
                if number is not None and not -2**63 < number < 2**63:
                    raise ValueError(f"pairs[{k}]: frame number {number} is not an int64")
                out.append(_NO_NUMBER if number is None else number)
            score.append(np.nan if ref.score is None else ref.score)
        any_ids = any(i >= 0 for i in id0) or any(i >= 0 for i in id1)
        numbers = int_column(np.array(number0 + number1, dtype=np.int64))
        any_numbers = bool(numbers.size) and int(numbers.max()) != _NO_NUMBER
        return cls(list(scenes), np.array(scene, dtype=np.int32),
                   frame_ids=list(frames) if any_ids else None,
                   id0=np.array(id0, dtype=np.int32) if any_ids else None,
                   id1=np.array(id1, dtype=np.int32) if any_ids else None,
                   number0=numbers[:len(number0)] if any_numbers else None,
                   number1=numbers[len(number0):] if any_numbers else None,
                   score=(np.array(score, dtype=np.float64)
                          if any(x == x for x in score) else None))

    @classmethod
    def concatenate(cls, parts: Sequence["PairIndex"]) -> "PairIndex":
        """The pairs of ``parts`` one after the other (scenes and frame ids merged by name)."""
        if len(parts) == 1:
            return parts[0]
        scenes: Dict[str, int] = {}
        frames: Dict[str, int] = {}
        scene: List[np.ndarray] = []
        ids0: List[np.ndarray] = []
        ids1: List[np.ndarray] = []
        numbers0: List[np.ndarray] = []
        numbers1: List[np.ndarray] = []
        scores: List[np.ndarray] = []
        any_ids = any(p.frame_ids is not None for p in parts)
        any_numbers = any(p.number0 is not None for p in parts)
        any_score = any(p.score is not None for p in parts)
        for p in parts:
            n = len(p)
            remap = np.array([scenes.setdefault(name, len(scenes)) for name in p.scenes],
                             dtype=np.int32)
            scene.append(remap[p.scene] if n else p.scene)
            if any_ids:
                if p.frame_ids is None or p.id0 is None or p.id1 is None:
                    ids0.append(np.full(n, -1, np.int32))
                    ids1.append(np.full(n, -1, np.int32))
                else:
                    # -1 (no id) maps to -1: the table's last entry.
                    table = np.array([frames.setdefault(f, len(frames)) for f in p.frame_ids]
                                     + [-1], dtype=np.int32)
                    ids0.append(table[p.id0])
                    ids1.append(table[p.id1])
            if any_numbers:
                for out, column in ((numbers0, p.number0), (numbers1, p.number1)):
                    out.append(np.full(n, _NO_NUMBER, np.int64) if column is None
                               else column.astype(np.int64))
            if any_score:
                scores.append(np.full(n, np.nan) if p.score is None else p.score)
        numbers = (int_column(np.concatenate(numbers0 + numbers1)) if any_numbers
                   else None)
        total = sum(len(p) for p in parts)
        return cls(list(scenes), np.concatenate(scene) if scene else np.zeros(0, np.int32),
                   frame_ids=list(frames) if any_ids else None,
                   id0=np.concatenate(ids0) if any_ids else None,
                   id1=np.concatenate(ids1) if any_ids else None,
                   number0=None if numbers is None else numbers[:total],
                   number1=None if numbers is None else numbers[total:],
                   score=np.concatenate(scores) if any_score else None)

    _noun = "pairs"

    def _slice(self, i: slice) -> "PairIndex":
        def cut(column: Optional[np.ndarray]) -> Optional[np.ndarray]:
            return None if column is None else column[i]
        return PairIndex(self.scenes, self.scene[i], frame_ids=self.frame_ids,
                         id0=cut(self.id0), id1=cut(self.id1), number0=cut(self.number0),
                         number1=cut(self.number1), score=cut(self.score))

    def _item(self, k: int) -> PairRef:
        frames: List[Optional[str]] = [None, None]
        if self.frame_ids is not None and self.id0 is not None and self.id1 is not None:
            frames = [None if j < 0 else self.frame_ids[j]
                      for j in (int(self.id0[k]), int(self.id1[k]))]
        numbers: List[Optional[int]] = [None, None]
        if self.number0 is not None and self.number1 is not None:
            numbers = [None if n == _NO_NUMBER else n
                       for n in (int(self.number0[k]), int(self.number1[k]))]
        score = None if self.score is None else float(self.score[k])
        return PairRef(self.scenes[int(self.scene[k])], frames[0], frames[1], numbers[0],
                       numbers[1], None if score is None or score != score else score)


def _read_npz(path: str, scene_names: Optional[Sequence[str]]) -> PairIndex:
    """LoFTR's scene_info npz (``name`` [N, 4], ``score``) or test.npz (``name``,
    ``rel_pose``): name = (scene number, sub-scene, frame number 0, frame number 1).

    Row (s, sub) names scene_names[s] when sub == 0 and s < len(scene_names), else ScanNet's
    scene{s:04d}_{sub:02d}: occgt's export numbers its non-ScanNet scenes 0, 1, ... (sub-scene
    0, scenes.txt) beside ScanNet scenes that keep their own numbers, and refuses a build
    where both would name one folder scene%04d_00 (loftr_export.cc, LoftrSceneFolders)."""
    try:
        with np.load(path, allow_pickle=False) as z:
            if "name" not in z.files:
                raise ValueError(f"{path}: no member 'name' (expected LoFTR's [N, 4] pair names)")
            name = z["name"]
            score = z["score"] if "score" in z.files else None
    except (OSError, ValueError) as e:
        if str(e).startswith(path):
            raise
        raise ValueError(f"{path}: cannot read as an npz pair index ({e})") from None
    if name.ndim != 2 or name.shape[1] != 4 or name.dtype.kind not in "iu":
        raise ValueError(f"{path}:name: expected integers of shape [N, 4] (scene, sub-scene, "
                         f"frame0, frame1), got {name.dtype} {list(name.shape)}")
    if score is not None and (score.shape != (name.shape[0],) or score.dtype.kind not in "fiu"):
        raise ValueError(f"{path}:score: expected shape [{name.shape[0]}] (numbers), got "
                         f"{score.dtype} {list(score.shape)}")
    if name.size and int(name.min()) < 0:
        r = int(np.argwhere(name < 0)[0][0])
        raise ValueError(f"{path}:name[{r}]: expected scene, sub-scene and frame numbers >= 0, "
                         f"got {name[r].tolist()}")
    if name.size and int(name.max()) >= 2**63:  # uint64 beyond int64: not a frame number
        r = int(np.argwhere(name >= np.uint64(2**63))[0][0])
        raise ValueError(f"{path}:name[{r}]: expected numbers below 2^63, got {name[r].tolist()}")
    if scene_names is None:
        names_file = _scene_names_file(path)
        scene_names = _read_scene_names(names_file) if names_file else None
    # Each (s, sub) once, in order of first appearance.
    scene_sub = name[:, :2].astype(np.int64)
    if not name.size or int(scene_sub.max()) < 2**31:  # one int64 key a row: a faster unique
        packed, first, inverse = np.unique((scene_sub[:, 0] << 32) | scene_sub[:, 1],
                                           return_index=True, return_inverse=True)
        keys = np.stack([packed >> 32, packed & (2**32 - 1)], axis=1)
    else:
        keys, first, inverse = np.unique(scene_sub, axis=0, return_index=True,
                                         return_inverse=True)
    order = np.argsort(first, kind="stable")
    rank = np.empty(len(order), np.int32)
    rank[order] = np.arange(len(order), dtype=np.int32)
    scenes: Dict[str, int] = {}  # two keys may name one scene (scenes.txt and ScanNet's name)
    scene_of_key = np.empty(len(order), np.int32)
    for k, (s, sub) in enumerate(keys[order].tolist()):
        if scene_names is not None and sub == 0 and s < len(scene_names):
            scene = scene_names[s]
        else:
            scene = f"scene{s:04d}_{sub:02d}"
        scene_of_key[k] = scenes.setdefault(scene, len(scenes))
    numbers = int_column(name[:, 2:].astype(np.int64))
    if score is not None and score.dtype.kind != "f":
        score = score.astype(np.float64)
    return PairIndex(list(scenes), scene_of_key[rank[inverse.reshape(-1)]],
                     number0=numbers[:, 0].copy(), number1=numbers[:, 1].copy(), score=score)


def _jsonl_refs(path: str) -> Iterator[PairRef]:
    """The pairs of occgt's pairs.jsonl or selection/<scene>.jsonl lines
    (schemas/pairs_line.schema.json), checked line by line."""
    with open(path, "rb") as f:
        for number, raw in enumerate(f, 1):
            try:
                line = raw.decode("utf-8")
                if not line.strip():
                    continue
                p = loads_strict(line)
                f0, f1 = p["frame0"], p["frame1"]  # frame records {id, number}
                for what, value, kind in (("scene", p["scene"], str), ("frame0.id", f0["id"], str),
                                          ("frame1.id", f1["id"], str),
                                          ("frame0.number", f0["number"], int),
                                          ("frame1.number", f1["number"], int)):
                    if not isinstance(value, kind) or isinstance(value, bool):
                        raise TypeError(f"{what}: expected {kind.__name__}, got {value!r}")
                for what, value in (("frame0.number", f0["number"]),
                                    ("frame1.number", f1["number"])):
                    if not -2**63 < value < 2**63:
                        raise TypeError(f"{what}: expected an int64, got {value!r}")
            except (ValueError, KeyError, TypeError) as e:
                raise ValueError(f"{path}:{number}: expected a pair line with scene, frame0, "
                                 f"frame1 as {{id, number}} ({type(e).__name__}: {e})") from None
            yield PairRef(p["scene"], f0["id"], f1["id"], f0["number"], f1["number"])


def _read_jsonl(path: str) -> PairIndex:
    return PairIndex.from_refs(_jsonl_refs(path))


def read_pair_index(pairs: Union[str, os.PathLike],
                    scene_names: Optional[Union[str, Sequence[str]]] = None,
                    npz_root: Optional[str] = None) -> PairIndex:
    """The pairs of an index, in its order, as a PairIndex (NumPy columns; item i a PairRef).

    ``pairs`` is one of: occgt's ``pairs.jsonl`` or a selection ``<scene>.jsonl``; a split
    folder (its ``pairs.jsonl``, else its ``selection/*.jsonl``); a LoFTR ``.npz`` (scene_info
    with ``name`` and ``score``, or test-1500's ``test.npz``); a folder of such npz files (LoFTR's
    ``scene_data/{split}``, sorted); a LoFTR list ``.txt`` (one npz name per line, in
    ``npz_root``, default the list's folder). LoFTR names scenes by number (s, sub):
    ``scene_names`` (a list, or a file with one name per line: line i = scene i; default
    occgt's export's ``scenes.txt`` when found beside the npz or two folders above it) names
    rows (s, 0) with s < len(scene_names); every other row is ScanNet's
    ``scene{s:04d}_{sub:02d}`` (occgt's export of ScanNet scenes mixed with others).
    """
    path = os.fspath(pairs)
    names = _read_scene_names(scene_names) if isinstance(scene_names, str) else scene_names
    if os.path.isdir(path):
        jsonl = os.path.join(path, "pairs.jsonl")
        if os.path.isfile(jsonl):
            return _read_jsonl(jsonl)
        selection = os.path.join(path, "selection")
        if os.path.isdir(selection):
            files = sorted(f for f in os.listdir(selection) if f.endswith(".jsonl"))
            return PairIndex.concatenate([_read_jsonl(os.path.join(selection, f))
                                          for f in files])
        npz = sorted(f for f in os.listdir(path) if f.endswith(".npz"))
        if not npz:
            raise ValueError(f"{path}: expected pairs.jsonl, selection/*.jsonl or LoFTR *.npz files")
        return PairIndex.concatenate([_read_npz(os.path.join(path, f), names) for f in npz])
    if not os.path.isfile(path):
        raise ValueError(f"{path}: no such pair index (expected a .jsonl, .npz or .txt)")
    if path.endswith(".jsonl"):
        return _read_jsonl(path)
    if path.endswith(".npz"):
        return _read_npz(path, names)
    if path.endswith(".txt"):
        root = npz_root if npz_root is not None else os.path.dirname(path)
        return PairIndex.concatenate([_read_npz(os.path.join(root, f), names)
                                      for f in _read_lines(path)])
    raise ValueError(f"{path}: unknown pair index type (expected .jsonl, .npz or .txt)")


class PairIndexDataset(torch.utils.data.Dataset):  # type: ignore[type-arg]
    """A map-style torch Dataset: item i = pair i of ``pairs`` with occgt's ground truth,
    computed on the fly from the dataset on disk (no shards).

    Args:
        pairs: the pair index (``read_pair_index``: pairs.jsonl, a split folder, a LoFTR npz,
            a folder of npz, a list file).
        root, format: the dataset (``occgt.open_dataset``; ``occgt.FORMATS``).
        width, height: the working resolution (pixels) of depth, images, K and labels.
        preset: label preset (``occgt.PRESETS``); ``**options`` are ``pair_ground_truth``'s
            keyword options (tolerances, ``stride``, ``anchor``, ``mutual``, occupancy
            settings); the depth range defaults to the scene's (as ``occgt pair``).
        images: also ``image0``/``image1``, grey [1, H, W] in [0, 1]: the library's colour at
            the working resolution (``Scene.load_color``, a shard's pixels) converted with
            ``cv2.COLOR_RGB2GRAY``. A frame without colour raises ValueError. A bool.
        image_format: ``"png"`` (the colour as it is: a PNG split's images) or ``"jpg"`` (the
            colour through occgt's JPEG encoding and OpenCV's decoding, as ShardDataset reads
            a split of ``sample.image: jpg``).
        occupancy: ``None`` (none), ``"words"`` (occ0/known0/occ1/known1, int64 views of the
            uint64 words) or ``"dense"`` (occupancy0/occupancy1 uint8 [D, H/2, W/2]).
        scope: the frames fused for occupancy (``Scene.fuse``): ``"pair"``, ``"window:N"``
            (fused for each item) or ``"scene:S"`` (fused when an item's scene is not the
            previous item's in this process, then shared by the scene's next pairs, as
            ``occgt build`` does; one map is kept: take items scene by scene).
        scene_names, npz_root: see ``read_pair_index``.
        depth_source, mesh_path, fused_depth: the frames' depth (``Scene.load``):
            ``"sensor"``, or ``"mesh"``/``"fused"`` with the scene's mesh (``mesh_path``,
            ``{scene}`` = the scene's name; None: the reader's) and, for ``"fused"``, the
            tolerances ``fused_depth`` (None: the defaults); pair scope only.
        device: ScanNet++'s camera, ``"dslr"`` or ``"iphone"`` (``occgt.open_dataset``).
        tum_max_dt_s: TUM's association tolerance (``occgt.open_dataset``; None: the default).

    Items are dicts with the keys of the sample contract (``occgt.torch``): LoFTR's keys
    (``T_0to1`` = cam1_from_cam0 computed from the two poses) and occgt's ground truth, plus
    ``pair_score`` (the index's score, NaN when it has none). ``pair_names`` are
    ``("<scene>/<frame id>", ...)``. Scenes are opened lazily, once per process (worker).
    """

    def __init__(self, pairs: Union[str, os.PathLike, Sequence[PairRef]], root: str, format: str,
                 *, width: int = occgt.PAIR_DEFAULTS["width"],
                 height: int = occgt.PAIR_DEFAULTS["height"],
                 preset: str = occgt.PAIR_DEFAULTS["preset"],
                 images: bool = True, image_format: str = "png",
                 occupancy: Optional[str] = None, scope: str = "pair",
                 scene_names: Optional[Union[str, Sequence[str]]] = None,
                 npz_root: Optional[str] = None,
                 depth_source: str = occgt.DATASET_DEFAULTS["depth_source"],
                 mesh_path: Optional[str] = None,
                 fused_depth: Optional[Dict[str, float]] = None,
                 device: str = occgt.DATASET_DEFAULTS["device"],
                 tum_max_dt_s: Optional[float] = None, **options: Any) -> None:
        if depth_source not in ("sensor", "mesh", "fused"):
            raise ValueError(f"depth_source: expected 'sensor', 'mesh' or 'fused', got {depth_source!r}")
        if not isinstance(images, (bool, np.bool_)):  # "no" is not a bool (it was truthy)
            raise TypeError(f"images: expected a bool, got {type(images).__name__}")
        if image_format not in ("png", "jpg"):
            raise ValueError(f"image_format: expected 'png' or 'jpg', got {image_format!r}")
        # The name Scene.fuse gives it (a bad scope failed in the first item).
        scope = occgt.scope_name(scope)
        if depth_source != "sensor" and occupancy is not None and scope != "pair":
            raise ValueError("depth_source: a scope other than 'pair' fuses sensor depth; "
                             "use scope='pair' with depth_source " + repr(depth_source))
        self.depth_source, self.mesh_path, self.fused_depth = depth_source, mesh_path, fused_depth
        if occupancy not in (None, "words", "dense"):
            raise ValueError(f"occupancy: expected None, 'words' or 'dense', got {occupancy!r}")
        if occupancy is None and scope != "pair":
            raise ValueError(f"scope: {scope!r} is the frames fused for occupancy, which is off "
                             f"(occupancy=None); pass occupancy='words' or 'dense'")
        self.pairs: PairIndex = (read_pair_index(pairs, scene_names, npz_root)
                                 if isinstance(pairs, (str, os.PathLike))
                                 else pairs if isinstance(pairs, PairIndex)
                                 else PairIndex.from_refs(pairs))
        # Fail here, not in a worker: the size, and the options as pair_ground_truth resolves
        # them (a misspelt or unknown option, a bad preset or value).
        check_resolution(width, height)
        resolved = occgt.pair_options(preset, occupancy=occupancy is not None, **options)
        occupancy_options = resolved["occupancy_options"]
        if (scope != "pair" and occupancy_options is not None
                and occupancy_options["mode"] != "octomap"):
            raise ValueError(f"scope: {scope!r} fuses frames for occupancy_mode 'octomap' only "
                             f"(mode {occupancy_options['mode']!r} uses the pair's depth "
                             "alone): use scope='pair'")
        self.root, self.format, self.device = root, format, device
        self.tum_max_dt_s = tum_max_dt_s
        self.width, self.height = operator.index(width), operator.index(height)
        self.preset, self.images, self.occupancy = preset, bool(images), occupancy
        self.image_format = image_format
        self.scope = scope
        self._scene_map: Optional[Tuple[str, occgt.ScopeMap]] = None
        self.options = dict(options)
        # The bins of the dense volumes, as the C++ resolved them (bins=None: the default).
        self.bins: int = (occupancy_options["bins"]["num_bins"] if occupancy_options is not None
                          else occgt.PAIR_DEFAULTS["bins"])
        self.dataset_name = _DATASET_NAMES.get(format, format)
        self._dataset: Optional[occgt.Dataset] = None
        self._pid = -1
        self._scenes: Dict[str, Tuple[occgt.Scene, Dict[int, str]]] = {}
        # Fail here, not in a worker, on a bad root, format or device (the readers open the
        # root lazily: test it here).
        occgt.open_dataset(root, format, device=device, tum_max_dt_s=tum_max_dt_s)
        if not os.path.exists(root):
            raise ValueError(f"root: {root}: no such dataset folder or file")

    @classmethod
    def from_split(cls, split_dir: str, *, root: Optional[str] = None,
                   images: Optional[bool] = None, occupancy: Optional[str] = "recipe",
                   **overrides: Any) -> "PairIndexDataset":
        """The pairs of a built split (its ``pairs.jsonl``, else its ``selection/``) with the
        options of its recipe (``recipe.json``: resolution, label preset and overrides, depth
        range, patches, occupancy; the dataset's ScanNet++ device, depth source, mesh path
        and fused-depth tolerances), so that item i has the arrays of the split's sample i.

        ``root`` replaces the recipe's dataset root (a synthetic recipe reads
        ``split_dir/data``). ``images`` defaults to the recipe's (``sample.image`` not
        ``none``) and ``image_format`` to its ``sample.image``; ``occupancy="recipe"`` to its
        encoding (packed/both → ``"words"``, dense → ``"dense"``, none when the recipe has no
        occupancy). Other keyword arguments override any argument of the constructor taken
        from the recipe (``width``, ``preset``, ``scope``, ``stride``, ...); the recipe's
        ``occupancy.scope`` is kept (``scope``).
        """
        path = os.path.join(split_dir, "recipe.json")
        try:
            with open(path) as f:
                recipe = json.load(f)
            dataset, labels, patches = recipe["dataset"], recipe["labels"], recipe["patches"]
            occ, sample = recipe["occupancy"], recipe["sample"]
            width, height = recipe["resolution"]
        except (OSError, ValueError, KeyError, TypeError) as e:
            raise ValueError(f"{path}: expected the recipe.json of a built split ({e})") from None
        fmt = dataset["format"]
        if root is None:
            root = dataset["root"] or os.path.join(split_dir, "data")
        if fmt == "synthetic":
            fmt = "generic"  # the build generated it as generic manifests
        # How the build read the frames: the ScanNet++ camera, the depth source and its mesh.
        depth: Dict[str, Any] = {
            "depth_source": dataset.get("depth_source", occgt.DATASET_DEFAULTS["depth_source"]),
            "mesh_path": dataset.get("mesh_path"),
            "fused_depth": dataset.get("fused_depth"),
            "device": dataset.get("device", occgt.DATASET_DEFAULTS["device"]),
            "tum_max_dt_s": dataset.get("tum_max_dt_s")}
        # The recipe's keys under pair_ground_truth's names, as they are: the C++ resolves them
        # (truth::ResolvePairTruthOptions), as for the build. recipe.json writes a recipe's
        # .inf (no upper limit) as "inf": JSON has no infinity, and null is a key not given.
        def number(v: Any) -> Any:
            return float("inf") if v == "inf" else v
        options: Dict[str, Any] = {
            "stride": patches["stride"], "anchor": patches["anchor"], "mutual": patches["mutual"],
            "dataset_min_depth_m": number(dataset.get("min_depth_m")),
            "dataset_max_depth_m": number(dataset.get("max_depth_m"))}
        options.update({k: number(v) for k, v in labels["overrides"].items() if v is not None})
        with_occupancy = bool(occ["enabled"] and sample["occupancy"])
        if occupancy == "recipe":
            occupancy = ({"dense": "dense"}.get(occ["encoding"], "words")
                         if with_occupancy else None)
        scope = {"window": f"window:{occ.get('window')}",
                 "scene": f"scene:{occ.get('scene_stride')}"}.get(occ["scope"], "pair")
        if occupancy is not None:
            options["scope"] = scope
            options.update({"voxel_m": occ["voxel_m"], "max_range_m": occ.get("max_range_m"),
                            "near_m": occ["near_m"], "far_m": occ["far_m"], "bins": occ["bins"],
                            "spacing": occ["spacing"], "traversal": occ["traversal"],
                            "occupancy_mode": occ["mode"]})
            # The point filters: recipe.json has them only when on.
            options.update({k: occ[k] for k in ("downsample", "remove_outliers", "outlier_k",
                                                "outlier_stddev") if k in occ})
        arguments: Dict[str, Any] = {
            "pairs": split_dir, "root": root, "format": fmt, "width": width, "height": height,
            "preset": labels["preset"],
            "images": sample["image"] != "none" if images is None else images,
            "image_format": "jpg" if sample["image"] == "jpg" else "png",
            "occupancy": occupancy, **depth, **options}
        arguments.update(overrides)  # any of them: one value per argument
        return cls(**arguments)

    def __getstate__(self) -> Dict[str, Any]:
        """The readers and maps of this process stay here (a spawned DataLoader worker or a
        pickle opens its own; the C++ objects cannot be pickled)."""
        state = self.__dict__.copy()
        state.update(_dataset=None, _scenes={}, _scene_map=None, _pid=-1)
        return state

    def __len__(self) -> int:
        return len(self.pairs)

    def _scene(self, name: str) -> Tuple[occgt.Scene, Dict[int, str]]:
        if self._pid != os.getpid():  # a forked worker opens its own readers
            self._dataset = occgt.open_dataset(self.root, self.format, device=self.device,
                                               tum_max_dt_s=self.tum_max_dt_s)
            self._scenes = {}
            self._pid, self._scene_map = os.getpid(), None
        if name not in self._scenes:
            assert self._dataset is not None
            scene = self._dataset.scene(name)
            if self.mesh_path is not None:  # "{scene}" = the scene's name, as in a recipe
                scene.mesh_path = self.mesh_path.replace("{scene}", name)
            self._scenes[name] = (scene, {f.number: f.id for f in scene.frames})
        return self._scenes[name]

    def _index(self, index: int) -> int:
        """``index`` as an int in 0..len - 1 (negative ones count from the end), else
        TypeError / IndexError."""
        return item_index(index, len(self.pairs), "pairs")

    def frame_ids(self, index: int) -> Tuple[str, str]:
        """The frame ids of pair ``index`` (an index given by numbers is resolved in its scene)."""
        index = self._index(index)
        ref = self.pairs[index]
        scene, by_number = self._scene(ref.scene)

        def resolve(frame_id: Optional[str], number: Optional[int]) -> str:
            if frame_id is not None:
                # A line naming a frame by id and number: both must be the same frame (an
                # edited line used the id silently).
                if number is not None and by_number.get(number) != frame_id:
                    other = by_number.get(number)
                    raise ValueError(f"pair {index}: frame id {frame_id} and number {number} "
                                     f"do not name the same frame of scene {ref.scene} (number "
                                     f"{number} is " + (f"frame {other})" if other is not None
                                                        else "no frame of it)"))
                return frame_id
            if number not in by_number:
                raise ValueError(f"pair {index}: scene {ref.scene} has no frame number {number}")
            return by_number[number]

        return resolve(ref.frame0, ref.number0), resolve(ref.frame1, ref.number1)

    def _fused(self, scene: occgt.Scene, id0: str, id1: str,
               options: Dict[str, Any]) -> occgt.ScopeMap:
        """The scope's map of the pair; a scene scope's map is kept for the scene's next pairs."""
        if self.scope.startswith("scene:") and self._scene_map and self._scene_map[0] == scene.name:
            return self._scene_map[1]
        fused = occgt.fuse_scope(scene, id0, id1, self.width, self.height, self.scope,
                                 self.preset, options)
        if self.scope.startswith("scene:"):
            self._scene_map = (scene.name, fused)
        return fused

    def _options_for(self, scene: occgt.Scene) -> Dict[str, Any]:
        """pair_ground_truth's keyword arguments for a pair of ``scene``."""
        return {"dataset_depth_range": (scene.min_depth_m, scene.max_depth_m), **self.options}

    def pair_options(self, index: int) -> Dict[str, Any]:
        """The options item ``index`` is computed with, resolved by the C++ as for the build
        (``occgt.pair_options``: label_options, patch_options, occupancy_options, whose
        ``fusion.scope`` is the dataset's ``scope``)."""
        scene, _ = self._scene(self.pairs[self._index(index)].scene)
        options = occgt.pair_options(self.preset, occupancy=self.occupancy is not None,
                                     **self._options_for(scene))
        if options["occupancy_options"] is not None:  # pair_options takes no scope: the map's
            options["occupancy_options"]["fusion"]["scope"] = self.scope
        return options

    def __getitem__(self, index: int) -> Dict[str, Any]:
        index = self._index(index)
        try:
            return self._item(index)
        except ValueError as e:  # a bad frame in a worker: which item of the index it was
            if str(e).startswith(f"pair {index}:"):  # the index's own problem, named already
                raise
            ref = self.pairs[index]
            frames = [f if f is not None else str(n)
                      for f, n in ((ref.frame0, ref.number0), (ref.frame1, ref.number1))]
            raise ValueError(f"pair {index} ({ref.scene}: {frames[0]}, {frames[1]}): {e}") from None

    def _item(self, index: int) -> Dict[str, Any]:
        ref = self.pairs[index]
        scene, _ = self._scene(ref.scene)
        id0, id1 = self.frame_ids(index)
        depth0, K0, world_from_cam0 = scene.load(id0, self.width, self.height,
                                                 depth_source=self.depth_source,
                                                 fused_depth=self.fused_depth)
        depth1, K1, world_from_cam1 = scene.load(id1, self.width, self.height,
                                                 depth_source=self.depth_source,
                                                 fused_depth=self.fused_depth)
        options = self._options_for(scene)
        if self.occupancy is not None and self.scope != "pair":
            options["scope_map"] = self._fused(scene, id0, id1, options)
        truth: Dict[str, Any] = dict(occgt.pair_ground_truth(
            depth0, depth1, K0, K1, world_from_cam0, world_from_cam1, self.preset,
            occupancy=self.occupancy is not None, **options))
        sample: Dict[str, Any] = {}
        if self.images:
            for k, frame_id in (("image0", id0), ("image1", id1)):
                rgb = scene.load_color(frame_id, self.width, self.height)
                if self.image_format == "jpg":
                    grey = cv2.cvtColor(_jpeg_round_trip(rgb, f"pair {index} {frame_id}"),
                                        cv2.COLOR_BGR2GRAY).astype(np.float32) / 255.0
                else:
                    grey = cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY).astype(np.float32) / 255.0
                sample[k] = to_tensor(grey[None])
        T_0to1 = truth["T_0to1"]
        sample.update({
            "depth0": to_tensor(depth0), "depth1": to_tensor(depth1),
            "K0": to_tensor(K0.astype(np.float32)), "K1": to_tensor(K1.astype(np.float32)),
            "T_0to1": to_tensor(T_0to1.astype(np.float32)),
            "T_1to0": to_tensor(np.linalg.inv(T_0to1).astype(np.float32)),
            "dataset_name": self.dataset_name, "scene_id": ref.scene, "pair_id": index,
            "pair_names": (f"{ref.scene}/{id0}", f"{ref.scene}/{id1}"),
            "pair_score": float("nan") if ref.score is None else ref.score,
        })
        for k in ("label01", "label10", "cells0", "cells1", "match_xy"):
            sample[k] = to_tensor(truth[k])
        sample["matches"] = to_tensor(truth["matches"].astype(np.int64))
        sample["match_type"] = to_tensor(truth["match_type"].astype(np.int64))
        sample["metrics01"], sample["metrics10"] = truth["metrics01"], truth["metrics10"]
        if self.occupancy == "words":
            for k in ("occ0", "known0", "occ1", "known1"):
                sample[k] = to_tensor(truth[k])
        elif self.occupancy == "dense":
            for c in "01":
                sample["occupancy" + c] = to_tensor(
                    occgt.dense_volume(truth["occ" + c], truth["known" + c], self.bins))
        return sample


def _jpeg_round_trip(rgb: np.ndarray, where: str) -> np.ndarray:
    """BGR uint8 [H, W, 3]: ``rgb`` as a split of ``sample.image: jpg`` stores it (the bytes
    occgt build writes, ``encode_sample_color``) decoded as ShardDataset decodes it
    (``cv2.imdecode``)."""
    jpeg = np.frombuffer(occgt._occgt.encode_sample_color(rgb, "jpg"), np.uint8)
    bgr = cv2.imdecode(jpeg, cv2.IMREAD_COLOR)
    if bgr is None:
        raise ValueError(f"{where}: OpenCV could not decode the sample's JPEG")
    return bgr
