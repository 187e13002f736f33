"""Predictions with known answers made from a built split's shards, and the eval tests' JSON
helpers."""
import gzip
import io
import json
import os
import tarfile
from typing import Dict, Iterator, Tuple

import numpy as np


def iter_samples(split_dir: str) -> Iterator[Dict[str, object]]:
    """{"__key__", "json", "<field>.npy": array, ...} per sample, index.json order."""
    with open(os.path.join(split_dir, "index.json")) as f:
        index = json.load(f)
    for shard in index["shardlist"]:
        sample: Dict[str, object] = {}
        with tarfile.open(os.path.join(split_dir, shard["url"]), "r:") as tar:
            for m in tar:
                folder, _, base = m.name.rpartition("/")
                stem, _, field = base.partition(".")
                key = folder + "/" + stem
                if sample and sample["__key__"] != key:
                    yield sample
                    sample = {}
                sample["__key__"] = key
                data = tar.extractfile(m).read()
                if field.endswith(".gz"):  # sample.compression: deflate (the default)
                    field, data = field[:-3], gzip.decompress(data)
                if field == "json":
                    sample["json"] = json.loads(data)
                elif field.endswith(".npy"):
                    sample[field] = np.load(io.BytesIO(data), allow_pickle=False)
        if sample:
            yield sample


def truth_matches(sample: Dict[str, object]) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The sample's coarse ground-truth matches as keypoints: (kpts0, kpts1, type); vv/vo
    from the anchor of cell0 to match_xy, ov from match_xy to the anchor of cell1."""
    meta = sample["json"]
    s = meta["patch_options"]["stride"]
    cols = meta["resolution"][0] // s
    off = s // 2 if meta["patch_options"]["anchor"] == "center" else 0
    matches = sample["matches.npy"]
    typ = sample["match_type.npy"]
    xy = sample["match_xy.npy"].astype(np.float32)

    def anchor(c: np.ndarray) -> np.ndarray:
        return np.stack([(c % cols) * s + off, (c // cols) * s + off], 1).astype(np.float32)

    ov = (typ == 2)[:, None]
    k0 = np.where(ov, xy, anchor(matches[:, 0]))
    k1 = np.where(ov, anchor(matches[:, 1]), xy)
    return k0.astype(np.float32), k1.astype(np.float32), typ


def load_json(path: str) -> object:
    with open(path) as f:
        return json.load(f)


def check_eval_schema(doc: object, source_dir: str) -> None:
    """Validates an eval.json document against schemas/eval.schema.json."""
    import jsonschema
    with open(os.path.join(source_dir, "schemas", "eval.schema.json")) as f:
        schema = json.load(f)
    jsonschema.validate(doc, schema, cls=jsonschema.Draft202012Validator)
