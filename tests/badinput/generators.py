"""Builders of small valid inputs and the mutations that break them (tests/badinput/README.md).

Every case of cases.json starts from one base ("scannet", "tartanair", "sevenscenes", "tum",
"generic", "build", "covis", "pair", "empty") laid out in the case's scratch folder, then
applies its "mutate" operations in order. Bases are tiny and made here (or by `occgt synth`),
never copied from ../shared/data.

Layout of a case folder CASE:
  CASE/data/...        the dataset (or, for "build", a finished `occgt build` output in
                       CASE/out and its dataset in CASE/data; "covis": `occgt covis` in
                       CASE/out; "pair": `occgt pair` + `occgt occupancy` in CASE/pair)
  CASE/recipe.yaml     a valid recipe reading CASE/data as a generic dataset (with N-view
                       tuples for "covis")
  CASE/out/            where commands write
"""
import json
import os
import shutil
import struct
import zlib

import numpy as np
from PIL import Image

W, H = 64, 48  # size of the hand-made depth maps where the reader does not fix it


# ---------------------------------------------------------------------------------------
# small file writers

def write_text(path, text):
    os.makedirs(os.path.dirname(path) or ".", exist_ok=True)
    with open(path, "w") as f:
        f.write(text)


def write_bytes(path, data):
    os.makedirs(os.path.dirname(path) or ".", exist_ok=True)
    with open(path, "wb") as f:
        f.write(data)


def png16(path, width, height, value=1000):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    Image.fromarray(np.full((height, width), value, dtype=np.uint16)).save(path)


def png8(path, width, height, channels=3):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    shape = (height, width, channels) if channels > 1 else (height, width)
    Image.fromarray(np.full(shape, 128, dtype=np.uint8)).save(path)


def matrix_text(m):
    return "".join(" ".join(f"{v:.6f}" for v in row) + "\n" for row in m)


def pose(i):
    m = np.eye(4)
    m[0, 3] = 0.05 * i
    return m


def npy_bytes(header, data=b""):
    """A .npy file with a literal header dict text (version 1.0), padded the numpy way."""
    h = header.encode("latin1")
    pad = (64 - (10 + len(h) + 1) % 64) % 64
    h = h + b" " * pad + b"\n"
    return b"\x93NUMPY\x01\x00" + struct.pack("<H", len(h)) + h + data


def exr_bytes(width, height, channels, value=2.0, header_only=False):
    """Minimal uncompressed scanline OpenEXR with FLOAT channels (one line per block);
    `header_only`: the header and an all-zero line offset table, no pixels (a data window
    the file does not hold)."""
    def attr(name, type_name, payload):
        return name.encode() + b"\0" + type_name.encode() + b"\0" + struct.pack("<i", len(payload)) + payload

    names = sorted(channels)
    chlist = b"".join(n.encode() + b"\0" + struct.pack("<iBBBBii", 2, 0, 0, 0, 0, 1, 1)
                      for n in names) + b"\0"
    box = struct.pack("<iiii", 0, 0, width - 1, height - 1)
    header = (b"\x76\x2f\x31\x01" + struct.pack("<i", 2) +
              attr("channels", "chlist", chlist) +
              attr("compression", "compression", b"\0") +
              attr("dataWindow", "box2i", box) +
              attr("displayWindow", "box2i", box) +
              attr("lineOrder", "lineOrder", b"\0") +
              attr("pixelAspectRatio", "float", struct.pack("<f", 1.0)) +
              attr("screenWindowCenter", "v2f", struct.pack("<ff", 0.0, 0.0)) +
              attr("screenWindowWidth", "float", struct.pack("<f", 1.0)) + b"\0")
    if header_only:
        return header + b"\0" * (8 * height)
    line = b"".join(struct.pack("<f", value) * width for _ in names)
    start = len(header) + 8 * height
    block = 8 + len(line)
    offsets = b"".join(struct.pack("<Q", start + y * block) for y in range(height))
    blocks = b"".join(struct.pack("<ii", y, len(line)) + line for y in range(height))
    return header + offsets + blocks


def png_claim_bytes(width, height, bit_depth=16):
    """A structurally complete greyscale PNG whose IHDR claims width x height but whose
    IDAT holds only a few bytes of image data."""
    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data +
                struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))
    ihdr = struct.pack(">IIBBBBB", width, height, bit_depth, 0, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) +
            chunk(b"IDAT", zlib.compress(b"\0" * 16)) + chunk(b"IEND", b""))


def npz_bytes(members):
    """A stored .npz (zip) of {name: numpy array}, written with Python's zipfile."""
    import io
    import zipfile
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_STORED) as z:
        for name, arr in members.items():
            b = io.BytesIO()
            np.save(b, arr)
            z.writestr(name + ".npy", b.getvalue())
    return buf.getvalue()


# ---------------------------------------------------------------------------------------
# bases

def base_scannet(case, occgt, cache):
    d = os.path.join(case, "data", "scene0000_00")
    K = np.array([[50.0, 0, 31.5, 0], [0, 50.0, 23.5, 0], [0, 0, 1, 0], [0, 0, 0, 1]])
    write_text(os.path.join(d, "intrinsic", "intrinsic_depth.txt"), matrix_text(K))
    for i in range(4):
        write_text(os.path.join(d, "pose", f"{i}.txt"), matrix_text(pose(i)))
        png16(os.path.join(d, "depth", f"{i}.png"), W, H)
        png8(os.path.join(d, "color", f"{i}.png"), W, H)
    # a valid scene outside the dataset root (for the --scene ../outside cases)
    o = os.path.join(case, "outside")
    write_text(os.path.join(o, "intrinsic", "intrinsic_depth.txt"), matrix_text(K))
    write_text(os.path.join(o, "pose", "0.txt"), matrix_text(pose(0)))
    png16(os.path.join(o, "depth", "0.png"), W, H)


def base_tartanair(case, occgt, cache):
    d = os.path.join(case, "data", "abandonedfactory", "Easy", "P000")
    lines = []
    for i in range(4):
        np.save(os.path.join(_mk(d, "depth_left"), f"{i:06d}_left_depth.npy"),
                np.full((480, 640), 3.0, dtype=np.float32))
        png8(os.path.join(d, "image_left", f"{i:06d}_left.png"), 640, 480)
        lines.append(f"{0.05 * i:.6f} 0 0 0 0 0 1")
    write_text(os.path.join(d, "pose_left.txt"), "\n".join(lines) + "\n")


def base_sevenscenes(case, occgt, cache):
    d = os.path.join(case, "data", "seq-01")
    for i in range(4):
        stem = os.path.join(d, f"frame-{i:06d}")
        write_text(stem + ".pose.txt", matrix_text(pose(i)))
        png16(stem + ".depth.png", 640, 480)
        png8(stem + ".color.png", 640, 480)


def base_tum(case, occgt, cache):
    d = os.path.join(case, "data", "rgbd_dataset_freiburg1_xyz")
    depth, rgb, gt = ["# depth"], ["# rgb"], ["# timestamp tx ty tz qx qy qz qw"]
    for i in range(4):
        t = 1305031102.0 + 0.1 * i
        png16(os.path.join(d, "depth", f"{t:.6f}.png"), 640, 480, 5000)
        png8(os.path.join(d, "rgb", f"{t:.6f}.png"), 640, 480)
        depth.append(f"{t:.6f} depth/{t:.6f}.png")
        rgb.append(f"{t + 0.001:.6f} rgb/{t:.6f}.png")
        gt.append(f"{t + 0.002:.6f} {0.05 * i:.4f} 0 0 0 0 0 1")
    write_text(os.path.join(d, "depth.txt"), "\n".join(depth) + "\n")
    write_text(os.path.join(d, "rgb.txt"), "\n".join(rgb) + "\n")
    write_text(os.path.join(d, "groundtruth.txt"), "\n".join(gt) + "\n")


RECIPE = """name: badinput
split: bad
resolution: [64, 48]
dataset:
  format: generic
  root: data
  min_valid_depth_fraction: 0.1
selection:
  max_frame_gap: 2
  score_stride: 4
  overlap: [0.0, 1.0]
  pruning: {frustum: false, max_distance_m: 100, max_view_angle_deg: 180}
occupancy: {enabled: false}
sample: {image: png, depth: true, labels: true, occupancy: false}
shards: {samples_per_shard: 3}
"""


def base_generic(case, occgt, cache):
    """`occgt synth`: data/synth_000/scene.json, 8 frames of 64x48 npy depth + png colour."""
    src = os.path.join(cache, "generic")
    if not os.path.exists(src):
        occgt("synth", "--out", src, "--scenes", "1", "--frames", "8", "--resolution", f"{W}x{H}")
    shutil.copytree(src, os.path.join(case, "data"))
    write_text(os.path.join(case, "recipe.yaml"), RECIPE)


def base_build(case, occgt, cache):
    """A finished `occgt build` of RECIPE on the generic base: CASE/out holds the split."""
    src = os.path.join(cache, "build")
    if not os.path.exists(src):
        os.makedirs(src)
        base_generic(src, occgt, cache)
        occgt("build", "--json", os.path.join(src, "recipe.yaml"), "--out", os.path.join(src, "out"))
    shutil.copytree(src, case, dirs_exist_ok=True, symlinks=True)


# RECIPE with N-view tuples (`occgt covis` / `occgt tuples`): every pair of the 8 frames is
# scored (no frustum, distance or angle pruning).
TUPLES_RECIPE = RECIPE.replace("""  pruning: {frustum: false, max_distance_m: 100, max_view_angle_deg: 180}
""", """  pruning: {frustum: false, max_distance_m: 100, max_view_angle_deg: 180}
  views: [2, 3]
  tuples: {edge_threshold: 0.05, restarts: 4, quota_per_scene: 4}
""")


def base_covis(case, occgt, cache):
    """`occgt covis` of TUPLES_RECIPE (CASE/recipe.yaml) on the generic base: CASE/out holds
    covisibility/synth_000.npz, which `occgt tuples CASE/recipe.yaml --out CASE/out` reads."""
    src = os.path.join(cache, "covis")
    if not os.path.exists(src):
        os.makedirs(src)
        base_generic(src, occgt, cache)
        write_text(os.path.join(src, "recipe.yaml"), TUPLES_RECIPE)
        occgt("covis", os.path.join(src, "recipe.yaml"), "--out", os.path.join(src, "out"))
    shutil.copytree(src, case, dirs_exist_ok=True, symlinks=True)


def base_tuples(case, occgt, cache):
    """`occgt tuples --shards` of TUPLES_RECIPE on the covis base: CASE/out/views holds the
    N-view split (`occgt validate CASE/out/views`)."""
    src = os.path.join(cache, "tuples")
    if not os.path.exists(src):
        os.makedirs(src)
        base_covis(src, occgt, cache)
        occgt("tuples", os.path.join(src, "recipe.yaml"), "--out", os.path.join(src, "out"),
              "--shards")
    shutil.copytree(src, case, dirs_exist_ok=True, symlinks=True)


def base_pair(case, occgt, cache):
    """`occgt pair` and `occgt occupancy` of frames 000000,000001 of the generic base into
    CASE/pair (the folder `occgt inspect pair --pair-dir` reads)."""
    src = os.path.join(cache, "pair")
    if not os.path.exists(src):
        os.makedirs(src)
        base_generic(src, occgt, cache)
        common = ["--root", os.path.join(src, "data"), "--format", "generic", "--scene", "synth_000",
                  "--frames", "000000,000001", "--resolution", f"{W}x{H}",
                  "--out", os.path.join(src, "pair")]
        occgt("pair", *common)
        occgt("occupancy", *common, "--voxel-m", "0.1")
    shutil.copytree(src, case, dirs_exist_ok=True, symlinks=True)


def base_empty(case, occgt, cache):
    os.makedirs(os.path.join(case, "data"), exist_ok=True)


BASES = {
    "scannet": base_scannet,
    "tartanair": base_tartanair,
    "sevenscenes": base_sevenscenes,
    "tum": base_tum,
    "generic": base_generic,
    "build": base_build,
    "covis": base_covis,
    "tuples": base_tuples,
    "pair": base_pair,
    "empty": base_empty,
}


def _mk(*parts):
    p = os.path.join(*parts)
    os.makedirs(p, exist_ok=True)
    return p


# ---------------------------------------------------------------------------------------
# mutations: {"op": NAME, ...}; paths are relative to the case folder

def _pointer(doc, pointer):
    """Parent container and last key of a JSON pointer ("/frames/1/K/0/0")."""
    parts = [p for p in pointer.split("/")[1:]]
    node = doc
    for p in parts[:-1]:
        node = node[int(p)] if isinstance(node, list) else node[p]
    last = parts[-1]
    return node, (last if isinstance(node, dict) else (last if last == "-" else int(last)))


def _load_json(path):
    with open(path) as f:
        return json.load(f)


def _dump_json(path, doc):
    with open(path, "w") as f:
        json.dump(doc, f)


def op_write(case, m):
    write_text(os.path.join(case, m["path"]), m["text"])


def op_write_bytes(case, m):
    write_bytes(os.path.join(case, m["path"]), bytes.fromhex(m["hex"]))


def op_remove(case, m):
    p = os.path.join(case, m["path"])
    if os.path.isdir(p) and not os.path.islink(p):
        shutil.rmtree(p)
    else:
        os.remove(p)


def op_make_folder(case, m):
    """Replaces a file by a folder of the same name (an unreadable file, even for root)."""
    p = os.path.join(case, m["path"])
    if os.path.lexists(p):
        op_remove(case, m)
    os.makedirs(p)


def op_symlink(case, m):
    p = os.path.join(case, m["path"])
    if os.path.lexists(p):
        op_remove(case, m)
    os.makedirs(os.path.dirname(p), exist_ok=True)
    os.symlink(m["target"], p)


def op_copy(case, m):
    shutil.copyfile(os.path.join(case, m["from"]), os.path.join(case, m["to"]))


def op_move(case, m):
    os.rename(os.path.join(case, m["from"]), os.path.join(case, m["to"]))


def op_truncate(case, m):
    p = os.path.join(case, m["path"])
    size = os.path.getsize(p)
    keep = m["keep"] if m["keep"] >= 0 else size + m["keep"]
    with open(p, "r+b") as f:
        f.truncate(keep)


def op_flip_byte(case, m):
    p = os.path.join(case, m["path"])
    with open(p, "r+b") as f:
        f.seek(m["offset"])
        b = f.read(1)
        f.seek(m["offset"])
        f.write(bytes([b[0] ^ 0xFF]))


def op_replace(case, m):
    """Text replacement; "count" (default 1) occurrences must exist."""
    p = os.path.join(case, m["path"])
    with open(p) as f:
        text = f.read()
    count = m.get("count", 1)
    assert text.count(m["old"]) >= count, f"{p}: '{m['old']}' not found {count} time(s)"
    with open(p, "w") as f:
        f.write(text.replace(m["old"], m["new"], count))


def op_json_set(case, m):
    p = os.path.join(case, m["path"])
    doc = _load_json(p)
    node, key = _pointer(doc, m["pointer"])
    node[key] = m["value"]
    _dump_json(p, doc)


def op_json_copy(case, m):
    """Copies the value at "from" to "to" (a pointer ending in "-" appends to a list)."""
    p = os.path.join(case, m["path"])
    doc = _load_json(p)
    src, skey = _pointer(doc, m["from"])
    value = json.loads(json.dumps(src[skey]))
    node, key = _pointer(doc, m["to"])
    if key == "-":
        node.append(value)
    else:
        node[key] = value
    _dump_json(p, doc)


def op_jsonl_set(case, m):
    """Sets key `key` of line `line` (0-based) of a JSONL file."""
    p = os.path.join(case, m["path"])
    with open(p) as f:
        lines = f.read().splitlines()
    doc = json.loads(lines[m["line"]])
    doc[m["key"]] = m["value"]
    lines[m["line"]] = json.dumps(doc, separators=(",", ":"))
    write_text(p, "\n".join(lines) + "\n")


def op_jsonl_drop(case, m):
    p = os.path.join(case, m["path"])
    with open(p) as f:
        lines = f.read().splitlines()
    del lines[m["line"]]
    write_text(p, "\n".join(lines) + "\n")


def op_npy(case, m):
    """A raw .npy with a literal header and `data_bytes` zero bytes of data."""
    write_bytes(os.path.join(case, m["path"]), npy_bytes(m["header"], b"\0" * m.get("data_bytes", 0)))


def op_npy_array(case, m):
    """np.save of an array of `shape`, `dtype` (numpy name), filled with `value`."""
    p = os.path.join(case, m["path"])
    os.makedirs(os.path.dirname(p), exist_ok=True)
    arr = np.full(m["shape"], m.get("value", 2.0), dtype=np.dtype(m["dtype"]))
    if m.get("fortran"):
        arr = np.asfortranarray(arr.reshape(m["shape"]))
    with open(p, "wb") as f:
        np.save(f, arr)


def op_npz(case, m):
    """A .npz with members {name: {"shape", "dtype", "value"}} (arrays filled with value)."""
    members = {k: np.full(v["shape"], v.get("value", 0), dtype=np.dtype(v["dtype"]))
               for k, v in m["members"].items()}
    write_bytes(os.path.join(case, m["path"]), npz_bytes(members))


def op_npz_raw(case, m):
    """A stored .npz whose one member is a raw .npy with a literal header and no data."""
    import io
    import zipfile
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_STORED) as z:
        z.writestr(m["member"], npy_bytes(m["header"]))
    write_bytes(os.path.join(case, m["path"]), buf.getvalue())


def op_npz_member(case, m):
    """Replaces member `member` (no .npy suffix) of an existing .npz: with a raw .npy of a
    literal `header` and `data_bytes` zero bytes, or with the member's own shape and dtype
    filled with `fill` (a number, "nan", or a string for a string array)."""
    import io
    import zipfile
    p = os.path.join(case, m["path"])
    with zipfile.ZipFile(p) as z:
        members = {n: z.read(n) for n in z.namelist()}
    name = m["member"] + ".npy"
    assert name in members, f"{p}: no member {name}"
    if "header" in m:
        members[name] = npy_bytes(m["header"], b"\0" * m.get("data_bytes", 0))
    else:
        arr = np.load(io.BytesIO(members[name]))
        b = io.BytesIO()
        np.save(b, np.full_like(arr, m["fill"]))
        members[name] = b.getvalue()
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_STORED) as z:
        for n, data in members.items():
            z.writestr(n, data)
    write_bytes(p, buf.getvalue())


def op_tar_size_field(case, m):
    """Rewrites the size field of the first ustar header (octal text) with a valid checksum."""
    p = os.path.join(case, m["path"])
    with open(p, "r+b") as f:
        header = bytearray(f.read(512))
        header[124:136] = m["octal"].encode().rjust(11, b"0") + b"\0"
        header[148:156] = b" " * 8
        header[148:156] = b"%06o\0 " % sum(header)
        f.seek(0)
        f.write(header)


def op_png16(case, m):
    png16(os.path.join(case, m["path"]), m["width"], m["height"], m.get("value", 1000))


def op_png_claim(case, m):
    write_bytes(os.path.join(case, m["path"]), png_claim_bytes(m["width"], m["height"]))


def op_jpeg(case, m):
    """A noisy RGB JPEG (quality 90; `progressive` optional)."""
    p = os.path.join(case, m["path"])
    os.makedirs(os.path.dirname(p), exist_ok=True)
    rgb = (np.random.RandomState(0).rand(m["height"], m["width"], 3) * 255).astype(np.uint8)
    Image.fromarray(rgb).save(p, quality=90, progressive=m.get("progressive", False))


def op_png8(case, m):
    png8(os.path.join(case, m["path"]), m["width"], m["height"], m.get("channels", 1))


def op_exr(case, m):
    write_bytes(os.path.join(case, m["path"]),
                exr_bytes(m["width"], m["height"], m["channels"], m.get("value", 2.0),
                          m.get("header_only", False)))


def op_shard_member(case, m):
    """Edits member `field` (plain name: "label01.npy", "json") of the first sample of shard
    `path` and records the shard's new size and MD5 in index.json beside it, so that only the
    values are wrong: "flat" + "value" set one item of a .npy member, "pointer" + "value" one
    field of the json. The member keeps its compression (.gz or not)."""
    import io

    import common  # tests/integration (badinput_test.py puts it on the path)

    def edit(plain):
        if m["field"] == "json":
            doc = json.loads(plain)
            node, k = _pointer(doc, m["pointer"])
            node[k] = m["value"]
            return json.dumps(doc).encode()
        arr = np.load(io.BytesIO(plain))
        arr.reshape(-1)[m["flat"]] = m["value"]
        buf = io.BytesIO()
        np.save(buf, arr)
        return buf.getvalue()

    common.edit_first_sample_member(os.path.join(case, m["path"]), m["field"], edit)


def op_mkdirs(case, m):
    os.makedirs(os.path.join(case, m["path"]), exist_ok=True)


OPS = {name[3:]: fn for name, fn in globals().items() if name.startswith("op_")}


def build_case(case_dir, spec, occgt, cache):
    BASES[spec["base"]](case_dir, occgt, cache)
    for m in spec.get("mutate", []):
        if m["op"] not in OPS:
            raise KeyError(f"case {spec['id']}: unknown op {m['op']}")
        OPS[m["op"]](case_dir, m)
