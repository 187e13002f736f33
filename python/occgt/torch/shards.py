"""ShardDataset: map-style random access into the shards of one split built by ``occgt build``.

The split folder's ``index.json`` lists the shards (docs/READING_SHARDS.md). At construction
the C++ shard reader lists every shard once (``occgt._occgt.shard_samples``: libgt/shards
``ListShardSamples``, one pass over the tar headers with libarchive, seeking past the data,
without the GIL) and gives the byte range of every member of every sample; nothing else is
kept. A sample's members are consecutive in its tar, so ``ds[i]`` reads them with one
``os.preadv`` into one buffer, parses the ``.npy`` members in place (the header by the C++,
``occgt._occgt.npy_header`` = libgt/io ``ParseNpyHeader``; the dtype by numpy; the data
``np.frombuffer``; a compressed ``.npy.gz`` member of ``sample.compression: deflate``, the
default, is inflated first by libdeflate in C++ into its own buffer, an uncompressed one is
copied out of the sample's buffer, so that a tensor kept from an item holds its own bytes,
not the whole sample's), the ``json`` member with
``json`` and the images with OpenCV (``python3-opencv``), and yields the sample contract of
``occgt.torch`` (see its docstring). Files are opened lazily in each process, so a
``DataLoader`` with worker processes never shares a file handle across ``fork``.
"""
from __future__ import annotations

import json
import math
import os
from typing import Any, Dict, List, Optional, Tuple, Union

import numpy as np
import torch.utils.data

from .._occgt import check_pair_sample, gunzip_npy, npy_header, shard_index, shard_samples
from ._convert import item_index, to_tensor

__all__ = ["ShardDataset"]

_OCCUPANCY_MODES = ("words", "dense", "none")
_NPY_MAGIC = b"\x93NUMPY"
_DTYPES: Dict[str, np.dtype] = {}  # descr -> numpy's dtype, for the few descrs of a split


class _Sample:
    """Where one sample's members are: shard number, byte range and the members in it."""

    __slots__ = ("shard", "start", "length", "members")

    def __init__(self, shard: int, start: int, length: int,
                 members: Dict[str, Tuple[int, int]]) -> None:
        self.shard = shard
        self.start = start
        self.length = length
        self.members = members


def _index_shard(path: str, shard: int, expected_size: int,
                 samples: List[_Sample], keys: List[str]) -> int:
    """Appends the samples of one shard to samples/keys; returns how many it holds."""
    try:
        size = os.stat(path).st_size
    except FileNotFoundError:
        raise ValueError(f"{path}: shard missing (index.json lists it)") from None
    if size != expected_size:
        how = "shorter" if size < expected_size else "longer"
        raise ValueError(f"{path}: {size} bytes, {how} than index.json's filesize "
                         f"{expected_size}")
    # The C++ reader (ValueError naming the shard and the member or header on a bad tar).
    listed = shard_samples(path)
    for key, start, length, members in listed:
        samples.append(_Sample(shard, start, length, members))
        keys.append(key)
    return len(listed)


def _has(members: Dict[str, Tuple[int, int]], field: str) -> bool:
    """Whether the sample holds `field`, as is or compressed ("<field>.gz")."""
    return field in members or field + ".gz" in members


def _bin_edges(occupancy: Dict[str, Any]) -> List[float]:
    """The bin edges of a sample json's "occupancy" object: ``bins.edges_m`` (occupancy.json's
    name), or ``bin_edges_m`` in samples written before; KeyError when neither is there."""
    if "bins" in occupancy:
        return list(occupancy["bins"]["edges_m"])
    return list(occupancy["bin_edges_m"])


def _grid(meta: Dict[str, Any]) -> Tuple[Optional[int], Optional[int]]:
    """(H/2, W/2) of the occupancy rays: the json's occupancy.grid [W/2, H/2]; any when
    the sample has none."""
    try:
        w, h = meta["occupancy"]["grid"]
        return int(h), int(w)
    except (KeyError, TypeError, ValueError):
        return None, None


def _npy(buf: bytearray, offset: int, size: int, where: str) -> np.ndarray:
    """The array of a ``.npy`` member at buf[offset:offset + size], sharing buf's memory.

    The header is parsed by the C++ (``npy_header``: magic, version, the header dict), the
    dtype is numpy's of its descr (any numpy dtype but objects; either byte order; Fortran
    order too)."""
    if buf[offset:offset + 6] != _NPY_MAGIC or size < 10:  # this error's words, before the C++
        raise ValueError(f"{where}: expected a .npy file (magic \\x93NUMPY)")
    try:
        descr, fortran, shape, start = npy_header(buf, offset, size, where)
        dtype = _DTYPES.get(descr)
        if dtype is None:
            dtype = _DTYPES.setdefault(descr, np.lib.format.descr_to_dtype(descr))
    except (TypeError, ValueError) as e:
        detail = str(e)
        if detail.startswith(where + ": "):
            detail = detail[len(where) + 2:]
        raise ValueError(f"{where}: bad .npy header: {detail}") from None
    if dtype.hasobject:
        raise ValueError(f"{where}: expected a plain dtype, got {dtype} (objects are refused)")
    count = math.prod(shape)
    if start + count * dtype.itemsize > size:
        raise ValueError(f"{where}: {shape} {dtype} needs {count * dtype.itemsize} bytes, "
                         f"the member holds {size - start}")
    array = np.frombuffer(buf, dtype=dtype, count=count, offset=offset + start)
    return array.reshape(shape, order="F" if fortran else "C")


class _ShardSplit(torch.utils.data.Dataset):  # type: ignore[type-arg]
    """The shards of one split folder (its ``index.json``), listed once by the C++ shard
    reader; a sample's members are read with one ``os.preadv`` by byte range. The base of
    ShardDataset (pair samples) and TupleShardDataset (N-view samples)."""

    def __init__(self, split_dir: Union[str, "os.PathLike[str]"]) -> None:
        self.split_dir = os.fspath(split_dir)
        # The C++ reader of index.json (ValueError naming it and the field at fault).
        _, _, shardlist = shard_index(self.split_dir)
        self._paths: List[str] = []
        self._samples: List[_Sample] = []
        self._keys: List[str] = []
        for n, (url, nsamples, filesize) in enumerate(shardlist):
            path = os.path.join(self.split_dir, url)
            got = _index_shard(path, n, filesize, self._samples, self._keys)
            if got != nsamples:
                raise ValueError(f"{path}: {got} samples, index.json says {nsamples}")
            self._paths.append(path)
        self._pairs: Optional[List[str]] = None
        self._pid = -1
        self._fds: Dict[int, int] = {}

    def __len__(self) -> int:
        return len(self._samples)

    def _index(self, i: int) -> int:
        return item_index(i, len(self._samples), "samples", "sample index")

    def key(self, i: int) -> str:
        """The sample key (``<scene>/<frame0>_<frame1>``) of sample i."""
        return self._keys[self._index(i)]

    def pair(self, i: int) -> Dict[str, Any]:
        """Sample i's line of ``pairs.jsonl`` (scene, frame ids, metrics, shard, key)."""
        j = self._index(i)
        if self._pairs is None:
            path = os.path.join(self.split_dir, "pairs.jsonl")
            try:
                with open(path, encoding="utf-8", errors="replace") as f:  # bad line: below
                    lines = f.read().splitlines()
            except FileNotFoundError:
                raise ValueError(f"{path}: missing (expected one line per sample)") from None
            if len(lines) != len(self._samples):
                raise ValueError(f"{path}: {len(lines)} lines, expected {len(self._samples)} "
                                 f"(one per sample of index.json's shards)")
            self._pairs = lines
        try:
            line = json.loads(self._pairs[j])
        except ValueError:  # not JSON (or not UTF-8)
            line = None
        if not isinstance(line, dict) or line.get("key") != self._keys[j]:
            raise ValueError(f"{os.path.join(self.split_dir, 'pairs.jsonl')}: line {j + 1}: "
                             f"expected a JSON object with key {self._keys[j]!r}")
        return line

    def _fd(self, shard: int) -> int:
        pid = os.getpid()
        if pid != self._pid:  # first use in this process (e.g. a forked DataLoader worker)
            for inherited in self._fds.values():  # this process's copies of the parent's
                try:
                    os.close(inherited)
                except OSError:
                    pass
            self._fds = {}
            self._pid = pid
        fd = self._fds.get(shard)
        if fd is None:
            try:
                fd = os.open(self._paths[shard], os.O_RDONLY)
            except FileNotFoundError:
                raise ValueError(f"{self._paths[shard]}: shard missing (removed since it was "
                                 f"indexed)") from None
            self._fds[shard] = fd
        return fd

    def read_raw(self, i: int) -> Tuple[bytearray, Dict[str, Tuple[int, int]]]:
        """The bytes of sample i's members (one read) and each member's (offset, size) in them."""
        sample = self._samples[self._index(i)]
        buf = bytearray(sample.length)
        got = os.preadv(self._fd(sample.shard), [buf], sample.start)
        if got != sample.length:
            raise ValueError(f"{self._paths[sample.shard]}: read {got} of {sample.length} bytes "
                             f"at byte {sample.start} (the shard changed since it was indexed)")
        return buf, sample.members

    def _read(self, i: int) -> Tuple[int, bytearray, Dict[str, Tuple[int, int]], str, bytes]:
        """Sample i's position, bytes and member ranges (read_raw), its name for messages
        (``<shard>: <key>``) and its ``json`` member's bytes."""
        j = self._index(i)
        buf, members = self.read_raw(j)
        offset, size = members["json"]
        return (j, buf, members, f"{self._paths[self._samples[j].shard]}: {self._keys[j]}",
                bytes(memoryview(buf)[offset:offset + size]))

    def _array(self, buf: bytearray, members: Dict[str, Tuple[int, int]], field: str,
               where: str, dtype: str, shape: Tuple[Optional[int], ...],
               size_text: str) -> np.ndarray:
        """The ``.npy`` member `field` (or its ``.gz``) of a sample read by read_raw, checked
        against the contract: dtype (numpy's ``str`` without the byte order, e.g. ``"f4"``;
        either byte order) and shape (None: any length); size_text says where the expected
        shape comes from."""
        if field in members:
            offset, size = members[field]
            # A copy: a view would keep the whole sample's buffer (images, depth, occupancy)
            # alive as long as any tensor of the item is kept (a trainer caching targets).
            a = _npy(buf, offset, size, f"{where}.{field}").copy()
            name = field
        else:  # a compressed member (recipe sample.compression: deflate): "<field>.gz"
            name = field + ".gz"
            offset, size = members[name]
            # libdeflate, without the GIL (C++).
            raw = gunzip_npy(memoryview(buf)[offset:offset + size], f"{where}.{name}")
            a = _npy(raw, 0, len(raw), f"{where}.{name}")
        if (a.dtype.str[1:] != dtype or a.ndim != len(shape) or
                any(n is not None and n != m for n, m in zip(shape, a.shape))):
            want = ", ".join("*" if n is None else str(n) for n in shape)
            raise ValueError(f"{where}.{name}: expected {np.dtype(dtype)} [{want}] "
                             f"({size_text}), got {a.dtype} {list(a.shape)}")
        return a

    def __getstate__(self) -> Dict[str, Any]:
        state = self.__dict__.copy()
        state["_fds"] = {}  # file descriptors never travel to another process
        state["_pid"] = -1
        return state

    def close(self) -> None:
        """Closes the files this process opened (they reopen on the next read)."""
        if self._pid == os.getpid():
            for fd in self._fds.values():
                os.close(fd)
        self._fds = {}

    def __del__(self) -> None:
        try:
            self.close()
        except (OSError, AttributeError):
            pass



class ShardDataset(_ShardSplit):
    """Map-style dataset over the shards of one split (``torch.utils.data.Dataset`` protocol).

    Args:
        split_dir: the split folder written by ``occgt build`` / ``occgt merge`` (holds
            ``index.json``, the ``.tar`` shards and ``pairs.jsonl``).
        occupancy, images, depth, labels: None (the default): what the split stores (its first
            sample's members: a split built with ``sample.depth: false``, the recipes'
            default, gives no depth; one without occupancy gives ``"none"``); a value asks for
            it, and a sample without it raises ValueError.
        occupancy: ``"words"``: ``occ0``, ``known0``, ``occ1``, ``known1`` int64 [H/2, W/2]
            (the uint64 words' bits); ``"dense"``: ``occupancy0``, ``occupancy1`` uint8
            [D, H/2, W/2] (0 free, 1 occupied, 255 unknown), the ``occ*_dense.npy`` member when
            the split stores it, else ``occgt.dense_volume`` of the words (C++); ``"none"``:
            no occupancy keys.
        images: ``image0``, ``image1`` float32 [1, H, W] grey in [0, 1]: the ``image0.png`` /
            ``.jpg`` member decoded by OpenCV, ``cv2.COLOR_BGR2GRAY``, divided by 255 (the
            contract's grey, as ``PairIndexDataset``'s).
        color: also ``color0``, ``color1`` uint8 [3, H, W] RGB.
        depth: ``depth0``, ``depth1`` float32 [H, W] metres, 0 = invalid.
        labels: ``label01``, ``label10`` uint8 [H, W] and ``cells0``, ``cells1`` uint8
            [H/s, W/s] (``matches``, ``match_type``, ``match_xy``, ``metrics01``,
            ``metrics10`` and the LoFTR keys are always there).
        dataset_name: the ``dataset_name`` value of every sample (shards do not record the
            dataset's format; LoFTR's evaluation picks thresholds by this name, e.g.
            ``"ScanNet"``).

    Raises:
        ValueError: naming the file and what was expected, when ``index.json`` is missing or
            malformed, a shard is missing, has another size than index.json says, is not a
            readable tar (the C++ reader's message: the header byte or member, e.g. a checksum
            mismatch or a truncated member) or holds another number of samples, or a sample
            lacks a member the options ask for; when an item is read, naming the sample and
            member, when a member has another dtype or shape than the contract's or its
            values disagree with the json or with each other (``occgt validate``'s value
            rules, in C++).
    """

    def __init__(self, split_dir: Union[str, "os.PathLike[str]"], *,
                 occupancy: Optional[str] = None, images: Optional[bool] = None,
                 color: bool = False, depth: Optional[bool] = None,
                 labels: Optional[bool] = None, dataset_name: str = "occgt") -> None:
        if occupancy is not None and occupancy not in _OCCUPANCY_MODES:
            raise ValueError(f"occupancy: expected one of {', '.join(_OCCUPANCY_MODES)}, got "
                             f"{occupancy!r}")
        # As TupleShardDataset: a str such as "no" is not a bool (it was truthy).
        for name, flag in (("images", images), ("color", color), ("depth", depth),
                           ("labels", labels)):
            if not isinstance(flag, (bool, np.bool_)) and not (flag is None and name != "color"):
                raise TypeError(f"{name}: expected a bool, got {type(flag).__name__}")
        if not isinstance(dataset_name, str):
            raise TypeError(f"dataset_name: expected a str, got {type(dataset_name).__name__}")
        self.color = bool(color)
        self.dataset_name = dataset_name
        super().__init__(split_dir)
        # Unset options: what the split stores (every sample of a split has the members its
        # recipe's `sample` section asks for: the first one's tell).
        first = self._samples[0].members if self._samples else {}
        self.occupancy = occupancy if occupancy is not None else (
            "words" if _has(first, "occ0.npy") else
            "dense" if _has(first, "occ0_dense.npy") else "none")
        self.images = bool(images) if images is not None else (
            "image0.png" in first or "image0.jpg" in first)
        self.depth = bool(depth) if depth is not None else _has(first, "depth0.npy")
        self.labels = bool(labels) if labels is not None else _has(first, "label01.npy")
        for i, sample in enumerate(self._samples):
            missing = self._missing(sample.members)
            if missing and _has(sample.members, "visible_in.npy"):
                raise ValueError(f"{self._paths[sample.shard]}: sample {self._keys[i]} is an "
                                 f"N-view sample (occgt tuples --shards, docs/MULTIVIEW.md); "
                                 f"ShardDataset reads the pair samples of occgt build, "
                                 f"TupleShardDataset the N-view ones")
            if missing:
                raise ValueError(f"{self._paths[sample.shard]}: sample {self._keys[i]} has no "
                                 f"{' or '.join(missing)} member (asked for by "
                                 f"{self._reason(missing[0])})")

    def _missing(self, members: Dict[str, Tuple[int, int]]) -> List[str]:
        need = ["json", "matches.npy", "match_type.npy", "match_xy.npy"]
        if self.labels:
            need += ["label01.npy", "label10.npy", "cells0.npy", "cells1.npy"]
        if self.depth:
            need += ["depth0.npy", "depth1.npy"]
        missing = [m for m in need if not _has(members, m)]
        if missing:
            return missing[:1]
        for c in "01":
            words = [f"occ{c}.npy", f"known{c}.npy"]
            if self.occupancy == "words" or (self.occupancy == "dense" and
                                             not _has(members, f"occ{c}_dense.npy")):
                for m in words:
                    if not _has(members, m):
                        return [m] if self.occupancy == "words" else [f"occ{c}_dense.npy", m]
            if (self.images or self.color) and not (f"image{c}.png" in members or
                                                    f"image{c}.jpg" in members):
                return [f"image{c}.png", f"image{c}.jpg"]
        return []

    def _reason(self, member: str) -> str:
        if member.startswith(("occ", "known")):
            return f"occupancy={self.occupancy!r}"
        if member.startswith("image"):
            return "images=True / color=True"
        if member.startswith("depth"):
            return "depth=True"
        if member.startswith(("label", "cells")):
            return "labels=True"
        return "every sample"

    def __getitem__(self, i: int) -> Dict[str, Any]:
        j, buf, members, where, meta_bytes = self._read(i)
        try:
            meta = json.loads(meta_bytes)
            T_0to1 = np.asarray(meta["T_0to1"], dtype=np.float64).reshape(4, 4)
            K0 = np.asarray(meta["K0"], dtype=np.float32).reshape(3, 3)
            K1 = np.asarray(meta["K1"], dtype=np.float32).reshape(3, 3)
            W, H = (int(n) for n in meta["resolution"])
            scene = str(meta["scene"])
            names = (f"{scene}/{meta['frame0']['id']}", f"{scene}/{meta['frame1']['id']}")
            metrics01, metrics10 = meta["metrics"]["01"], meta["metrics"]["10"]
            bins = (len(_bin_edges(meta["occupancy"])) - 1 if self.occupancy == "dense"
                    else 0)
        except (KeyError, TypeError, ValueError) as e:
            raise ValueError(f"{where}.json: expected the sample fields of "
                             f"schemas/sample.schema.json (T_0to1 4x4, K0/K1 3x3, resolution, "
                             f"scene, frame0/frame1 id, metrics 01/10, "
                             f"occupancy bins.edges_m for occupancy='dense'): "
                             f"{type(e).__name__}: {e}") from None
        grid = _grid(meta)

        read: Dict[str, np.ndarray] = {}  # the members read, checked below

        def member(field: str, dtype: str, shape: Tuple[Optional[int], ...]) -> np.ndarray:
            """The member, checked against the contract (schemas/sample.schema.json, the
            arrays of libgt/pipeline/sample.cc)."""
            read[field] = self._array(buf, members, field, where, dtype, shape,
                                      f"sample resolution {W}x{H}")
            return read[field]

        if self.depth:
            for c in "01":
                member(f"depth{c}.npy", "f4", (H, W))
        if self.labels:
            for name in ("label01", "label10"):
                member(name + ".npy", "u1", (H, W))
            for name in ("cells0", "cells1"):
                member(name + ".npy", "u1", (None, None))
        rows = member("matches.npy", "i4", (None, 2)).shape[0]
        member("match_type.npy", "u1", (rows,))
        member("match_xy.npy", "f4", (rows, 2))
        for c in "01":  # "dense": each camera's stored volume, else its words
            if self.occupancy == "dense" and _has(members, f"occ{c}_dense.npy"):
                member(f"occ{c}_dense.npy", "u1", (bins,) + grid)
            elif self.occupancy != "none":
                member(f"occ{c}.npy", "u8", grid)
                member(f"known{c}.npy", "u8", grid)
        # The json and these arrays against each other, in C++ (shards::CheckPairSampleValues:
        # poses and K, label codes and counts, depth against NO_DEPTH, cells, matches by their
        # rules, occupancy), so that a damaged sample never reaches a trainer.
        check_pair_sample(meta_bytes.decode("utf-8", "replace"), read, where)

        out: Dict[str, Any] = {}
        if self.images or self.color:
            for c in "01":
                field = f"image{c}.png" if f"image{c}.png" in members else f"image{c}.jpg"
                offset, size = members[field]
                data = np.frombuffer(buf, dtype=np.uint8, count=size, offset=offset)
                bgr = _decode(data, f"{where}.{field}", H, W)
                if self.images:
                    grey = _cv2().cvtColor(bgr, _cv2().COLOR_BGR2GRAY)
                    out["image" + c] = to_tensor(grey.astype(np.float32)[None] / 255.0)
                if self.color:
                    out["color" + c] = to_tensor(np.ascontiguousarray(
                        bgr[:, :, ::-1].transpose(2, 0, 1)))
        if self.depth:
            out["depth0"] = to_tensor(read["depth0.npy"])
            out["depth1"] = to_tensor(read["depth1.npy"])
        out["K0"] = to_tensor(K0)
        out["K1"] = to_tensor(K1)
        out["T_0to1"] = to_tensor(T_0to1.astype(np.float32))
        out["T_1to0"] = to_tensor(np.linalg.inv(T_0to1).astype(np.float32))
        out["dataset_name"] = self.dataset_name
        out["scene_id"] = scene
        out["pair_id"] = j
        out["pair_names"] = names
        if self.labels:
            for name in ("label01", "label10", "cells0", "cells1"):
                out[name] = to_tensor(read[name + ".npy"])
        out["matches"] = to_tensor(read["matches.npy"].astype(np.int64))
        out["match_type"] = to_tensor(read["match_type.npy"].astype(np.int64))
        out["match_xy"] = to_tensor(read["match_xy.npy"])
        if self.occupancy == "words":
            for name in ("occ0", "known0", "occ1", "known1"):
                out[name] = to_tensor(read[name + ".npy"])
        elif self.occupancy == "dense":
            for c in "01":
                if f"occ{c}_dense.npy" in read:
                    volume = read[f"occ{c}_dense.npy"]
                else:
                    from .. import dense_volume  # the C++ unpacking

                    volume = dense_volume(read[f"occ{c}.npy"], read[f"known{c}.npy"], bins)
                out["occupancy" + c] = to_tensor(volume)
        out["metrics01"] = metrics01
        out["metrics10"] = metrics10
        return out

def _cv2() -> Any:
    try:
        import cv2
    except ImportError:  # pragma: no cover - depends on the machine
        raise ImportError("occgt.torch.ShardDataset decodes images with OpenCV: install "
                          "python3-opencv, or pass images=False, color=False") from None
    return cv2


def _decode(data: np.ndarray, where: str, H: int, W: int) -> np.ndarray:
    """An encoded PNG/JPEG member -> uint8 [H, W, 3] BGR (OpenCV's order)."""
    cv2 = _cv2()
    image = cv2.imdecode(data, cv2.IMREAD_COLOR)
    if image is None:
        raise ValueError(f"{where}: not a decodable PNG/JPEG image")
    if image.shape[:2] != (H, W):
        raise ValueError(f"{where}: image is {image.shape[1]}x{image.shape[0]}, expected the "
                         f"sample's resolution {W}x{H}")
    return image
