#!/usr/bin/python3
"""Builds the seed corpus of every fuzz target (tests/fuzz/*_fuzz.cc) at run time.

usage: make_seeds.py OUT_DIR SHARED_DATA SOURCE_DIR

OUT_DIR/<target>/ gets copies of real samples from SHARED_DATA (../shared/data: never
committed to the project), the project's own fixtures and recipes from SOURCE_DIR, and
tiny seeds generated here (numpy for .npy/.npz, PIL for 16-bit PNG, a hand-built
uncompressed scanline OpenEXR file). Fails loudly when SHARED_DATA is missing.
"""
import glob
import io
import os
import shutil
import struct
import sys
import zipfile
import zlib

import numpy as np
from PIL import Image


def main():
    out, shared, src = sys.argv[1:4]
    if not os.path.isdir(shared):
        sys.exit(f"make_seeds.py: shared data folder {shared} is missing")
    counts = {}

    def put(target, name, data):
        d = os.path.join(out, target)
        os.makedirs(d, exist_ok=True)
        with open(os.path.join(d, name), "wb") as f:
            f.write(data)
        counts[target] = counts.get(target, 0) + 1

    def copy(target, paths, limit=None, prefix=""):
        paths = sorted(paths)
        if not paths:
            sys.exit(f"make_seeds.py: no seed files for {target} ({prefix})")
        for p in paths[:limit]:
            with open(p, "rb") as f:
                put(target, prefix + os.path.basename(p), f.read())

    # --- npy: one real TartanAir depth map (1.2 MB) and small arrays of every dtype.
    copy("npy", glob.glob(f"{shared}/tartanair/hospital_sample/depth_left/*.npy"), 1, "real_")
    rng = np.random.default_rng(0)
    for descr in ["<f4", "<f8", "|u1", "<u2", "<i4", "<i8", "|b1", "<f2"]:
        a = (rng.random((3, 4)) * 10).astype(np.dtype(descr))
        b = io.BytesIO()
        np.save(b, a)
        put("npy", f"small_{descr[1:]}.npy", b.getvalue())
    for shape in [(0,), (5,), (2, 3, 1), (1, 1)]:
        b = io.BytesIO()
        np.save(b, np.ones(shape, np.float32))
        put("npy", f"shape_{len(shape)}d_{shape[0]}.npy", b.getvalue())
    b = io.BytesIO()
    np.lib.format.write_array(b, np.ones((2, 2), np.float32), version=(2, 0))
    put("npy", "version2.npy", b.getvalue())

    # --- npz: LoFTR's test-1500 index and intrinsics (real), small stored/deflated ones.
    copy("npz", glob.glob(f"{shared}/loftr_scannet_test_1500/*.npz"), None, "real_")
    for compression, tag in [(zipfile.ZIP_STORED, "stored"), (zipfile.ZIP_DEFLATED, "deflated")]:
        b = io.BytesIO()
        with zipfile.ZipFile(b, "w", compression) as z:
            for key, arr in [("name", np.arange(8, dtype=np.uint16).reshape(2, 4)),
                             ("score", np.array([0.5, 0.25], np.float32))]:
                m = io.BytesIO()
                np.save(m, arr)
                z.writestr(key + ".npy", m.getvalue())
        put("npz", f"small_{tag}.npz", b.getvalue())

    # --- 4x4 poses and intrinsics: ScanNet (real), 7-Scenes (real), fixtures.
    copy("pose_matrix", glob.glob(f"{shared}/scannet_posed_color/scene_sample/pose/*.txt"), None,
         "scannet_")
    copy("pose_matrix", glob.glob(f"{shared}/scannet_posed_color/scene_sample/intrinsic/*.txt"),
         None, "scannet_K_")
    copy("pose_matrix", glob.glob(f"{shared}/sevenscenes/rgbd-frames/*.pose.txt"), 8, "7scenes_")
    copy("pose_matrix", [f"{shared}/sevenscenes/camera-intrinsics.txt"], None, "7scenes_K_")
    for p in sorted(glob.glob(f"{src}/tests/fixtures/io/scannet_*/*/*.txt")):
        with open(p, "rb") as f:
            put("pose_matrix", "fixture_" + p.split("/fixtures/io/")[1].replace("/", "_"),
                f.read())

    # --- quaternion lines: TartanAir pose_left.txt (real), fixture, TUM groundtruth.
    copy("tq_pose", [f"{shared}/tartanair/hospital_sample/pose_left.txt"], None, "tartanair_")
    copy("tq_pose", [f"{src}/tests/fixtures/io/tartanair_short_pose/pose_left.txt"], None,
         "fixture_")
    tum_gt = (b"# ground truth trajectory\n# timestamp tx ty tz qx qy qz qw\n"
              b"1305031102.1758 1.3405 0.6266 1.6575 0.6574 0.6126 -0.2949 -0.3248\n"
              b"1305031102.1858 1.3303 0.6256 1.6464 0.6579 0.6161 -0.2932 -0.3189\n"
              b"9.99 1 0 0 0 0 0 1\n10.51 5 0 0 0 0 0 2\n")
    put("tq_pose", "tum_groundtruth.txt", tum_gt)
    put("tq_pose", "lost.txt", b"0 0 0 nan nan nan nan\n1 2 3 0 0 0 1\n\n-inf 0 0 0 0 0 1\n")

    # --- TUM lists: depth.txt alone, and depth.txt \0 rgb.txt \0 groundtruth.txt.
    depth = (b"# depth maps\n# timestamp filename\n10.100000 depth/10.100000.png\n"
             b"10.000000 depth/10.000000.png\n10.200000 depth/10.200000.png\n")
    rgb = b"# color images\n10.005 rgb/10.005.png\n10.130 rgb/10.130.png\n"
    put("tum_list", "depth_only.txt", depth)
    put("tum_list", "sequence.bin", depth + b"\0" + rgb + b"\0" + tum_gt)
    put("tum_list", "dup_ids.bin", b"1.0 d/a.png\n2.0 e/a.png\n\0\0" + tum_gt)

    # --- generic manifests: fixtures and a small valid one.
    for p in sorted(glob.glob(f"{src}/tests/fixtures/io/generic_*/scene.json")):
        with open(p, "rb") as f:
            put("manifest", p.split("/")[-2] + ".json", f.read())
    put("manifest", "valid.json", b"""{"format": "occgt-scene-manifest", "version": 1,
 "scene": "s0", "depth_range_m": [0.1, 20],
 "frames": [{"id": "000000", "width": 160, "height": 120,
   "K": [[100, 0, 80], [0, 100, 60], [0, 0, 1]],
   "depth": {"path": "depth/000000.png", "format": "png16", "scale_m": 0.001, "invalid_value": 0},
   "world_from_cam": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]],
   "color": {"path": "color/000000.png", "width": 320, "height": 240,
             "K": [[200, 0, 160], [0, 200, 120], [0, 0, 1]]}},
  {"id": "000001", "width": 160, "height": 120,
   "K": [[100, 0, 80], [0, 100, 60], [0, 0, 1]],
   "depth": {"path": "d.exr", "format": "exr", "channel": "Depth.Z"},
   "world_from_cam": [[0, -1, 0, 1], [1, 0, 0, 2], [0, 0, 1, 3], [0, 0, 0, 1]]}]}
""")

    # --- recipes: the project's shipped recipes.
    copy("recipe", glob.glob(f"{src}/recipes/*.yaml"), None, "shipped_")
    put("recipe", "anchors.yaml", b"name: a\nx: &a [1, 2]\ndataset: {format: synthetic}\n"
                                  b"selection: {overlap: [0.1, 0.9], occlusion: *a}\n")

    # --- 16-bit PNG depth: one real 7-Scenes depth map, small generated ones, a PGM.
    copy("depth_png", glob.glob(f"{shared}/sevenscenes/rgbd-frames/*.depth.png"), 1, "real_")
    for w, h in [(4, 3), (1, 1), (16, 9)]:
        b = io.BytesIO()
        Image.fromarray((np.arange(w * h, dtype=np.uint16).reshape(h, w) * 97)).save(b, "PNG")
        put("depth_png", f"small_{w}x{h}.png", b.getvalue())
    b = io.BytesIO()
    Image.fromarray(np.zeros((3, 4), np.uint8)).save(b, "PNG")
    put("depth_png", "gray8.png", b.getvalue())
    put("depth_png", "small.pgm", b"P5\n4 3\n65535\n" + bytes(range(24)))

    # --- colour image headers: real colour images of the samples, small generated PNG, JPEG
    # (baseline and progressive) and Netpbm files.
    copy("image_size", glob.glob(f"{shared}/sevenscenes/rgbd-frames/*.color.png"), 1, "real_")
    copy("image_size", glob.glob(f"{shared}/scannet_posed_color/*/color/*.png"), 1, "real_scannet_")
    jpgs = glob.glob(f"{shared}/**/*.jpg", recursive=True)
    if jpgs:
        copy("image_size", jpgs, 1, "real_")
    rgb = np.arange(5 * 7 * 3, dtype=np.uint8).reshape(5, 7, 3)
    for fmt, opts, name in [("PNG", {}, "small.png"), ("JPEG", {}, "small.jpg"),
                            ("JPEG", {"progressive": True}, "progressive.jpg"),
                            ("PPM", {}, "small.ppm")]:
        b = io.BytesIO()
        Image.fromarray(rgb).save(b, fmt, **opts)
        put("image_size", name, b.getvalue())
    put("image_size", "comment.pgm", b"P5\n# a comment\n7 5\n255\n" + bytes(35))

    # --- colour image decoding: small files of every layout the decoder handles (real
    # images are 640x480 and would make each run slow).
    for fmt, opts, name in [("PNG", {}, "rgb.png"), ("JPEG", {"quality": 90}, "rgb.jpg"),
                            ("JPEG", {"progressive": True}, "progressive.jpg"),
                            ("PPM", {}, "rgb.ppm")]:
        b = io.BytesIO()
        Image.fromarray(rgb).save(b, fmt, **opts)
        put("image_decode", name, b.getvalue())
    grey = np.arange(5 * 7, dtype=np.uint8).reshape(5, 7) * 7
    for mode, name in [("L", "grey.png"), ("LA", "grey_alpha.png"), ("P", "palette.png"),
                       ("RGBA", "rgba.png"), ("1", "bilevel.png"), ("L", "grey.jpg")]:
        img = Image.fromarray(grey).convert(mode) if mode != "RGBA" else Image.fromarray(
            np.dstack([rgb, grey]))
        b = io.BytesIO()
        img.save(b, "JPEG" if name.endswith(".jpg") else "PNG")
        put("image_decode", name, b.getvalue())
    b = io.BytesIO()
    Image.fromarray((np.arange(12, dtype=np.uint16).reshape(3, 4) * 5000)).save(b, "PNG")
    put("image_decode", "grey16.png", b.getvalue())
    put("image_decode", "plain.pgm", b"P2\n# c\n3 2\n300\n0 7 300\n15 3 9\n")
    put("image_decode", "plain.ppm", b"P3 2 1 255  1 2 3  250 128 0\n")
    put("image_decode", "plain.pbm", b"P1\n3 2\n1 0 1\n001\n")
    put("image_decode", "raw.pbm", b"P4\n3 2\n\xa0\x3f")
    put("image_decode", "wide.pgm", b"P5\n4 3\n65535\n" + bytes(range(24)))

    # --- OpenEXR depth: uncompressed scanline files written by hand (no EXR writer in
    # Debian's python3), with the channel names Blender uses.
    for chans, tag in [(["Z"], "z"), (["View Layer.Depth.Z"], "blender"), (["R", "G", "B"], "rgb"),
                       (["Y", "A"], "ya")]:
        put("depth_exr", f"small_{tag}.exr", Exr(chans, 4, 3))
    put("depth_exr", "one_pixel.exr", Exr(["Z"], 1, 1))

    # --- ScanNet .sens: small files written by tests/support/write_sens.py (zlib and raw
    # depth, JPEG and raw colour, a lost-tracking frame).
    sys.path.insert(0, os.path.join(src, "tests", "support"))
    import write_sens
    frames, Kc, Kd, cs, ds = write_sens.synthetic_frames((16, 12), (8, 6))
    for cc, dc, tag in [(write_sens.COLOR_JPEG, write_sens.DEPTH_ZLIB, "jpeg_zlib"),
                        (write_sens.COLOR_RAW, write_sens.DEPTH_RAW, "raw_raw")]:
        fr = frames[:3] if cc != write_sens.COLOR_RAW else [
            (p, bytes(cs[0] * cs[1] * 3), d) for p, _, d in frames[:3]]
        path = os.path.join(out, "sens_tmp", tag + ".sens")
        write_sens.write_sens(path, fr, Kc, Kd, cs, ds, cc, dc)
        with open(path, "rb") as f:
            put("sens", tag + ".sens", f.read())
    shutil.rmtree(os.path.join(out, "sens_tmp"))

    # --- COLMAP sparse models (colmap_fuzz: the first byte picks the parser, 0 cameras.bin,
    # 1 images.bin, 2 cameras.txt, 3 images.txt), a tiny model in both forms.
    cams_bin = struct.pack("<Q", 2)
    cams_bin += struct.pack("<iiQQ", 1, 1, 64, 48) + struct.pack("<4d", 50, 52, 32, 24)
    cams_bin += struct.pack("<iiQQ", 2, 2, 40, 30) + struct.pack("<4d", 30, 20, 15, 0.01)
    imgs_bin = struct.pack("<Q", 2)
    imgs_bin += struct.pack("<i7di", 1, 1, 0, 0, 0, 0, 0, 0, 1) + b"a.jpg\0" + struct.pack("<Q", 0)
    imgs_bin += (struct.pack("<i7di", 2, 0.5 ** 0.5, 0, 0, 0.5 ** 0.5, 1, 2, 3, 2) + b"b.jpg\0" +
                 struct.pack("<Q", 1) + struct.pack("<ddq", 10.5, 20.5, -1))
    put("colmap", "cameras_bin", b"\x00" + cams_bin)
    put("colmap", "images_bin", b"\x01" + imgs_bin)
    put("colmap", "cameras_txt", b"\x02# cameras\n1 PINHOLE 64 48 50 52 32 24\n"
        b"2 SIMPLE_PINHOLE 40 30 30 20 15\n")
    put("colmap", "images_txt", b"\x03# images\n1 1 0 0 0 0 0 0 1 a.jpg\n\n"
        b"2 0.7071 0 0 0.7071 1 2 3 2 b.jpg\n10.5 20.5 -1\n")

    put("colmap", "cameras_txt_lenses", b"\x02# ScanNet++ DSLR and iPhone\n"
        b"1 OPENCV_FISHEYE 876 584 395.6 395.4 437.6 292.3 -0.0297 -0.0049 0.0011 -0.0004\n"
        b"2 OPENCV 480 360 361.3 361.2 240.3 180.0 0.05 -0.1 0.001 0.0005\n"
        b"3 SIMPLE_RADIAL 64 48 50 32 24 0.01\n")

    # --- PLY meshes (ply_fuzz): the real TSDF mesh's exact header (Open3D: double x y z,
    # `list uchar uint`) cut to its first 64 vertices and the faces among them; ASCII with
    # colours and a quad; big-endian float with normals, `list uchar int` and an extra element.
    real = f"{shared}/meshes/sevenscenes-rgbd-frames-tsdf.ply"
    with open(real, "rb") as f:
        data = f.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").splitlines()
    nv = int(next(h for h in header if h.startswith("element vertex")).split()[2])
    nf = int(next(h for h in header if h.startswith("element face")).split()[2])
    verts = np.frombuffer(data, "<f8", nv * 3, end).reshape(nv, 3)
    faces = np.frombuffer(data, np.dtype([("n", "u1"), ("i", "<u4", 3)]), nf, end + nv * 24)
    keep = 64
    small = faces[(faces["n"] == 3) & (faces["i"] < keep).all(axis=1)]
    head = "\n".join(f"element vertex {keep}" if h.startswith("element vertex") else
                     f"element face {len(small)}" if h.startswith("element face") else h
                     for h in header) + "\n"
    put("ply", "real_tsdf_head.ply", head.encode() + verts[:keep].tobytes() + small.tobytes())
    put("ply", "ascii_quad.ply", b"ply\nformat ascii 1.0\ncomment quad and triangle\n"
        b"element vertex 5\nproperty float x\nproperty float y\nproperty float z\n"
        b"property uchar red\nproperty uchar green\nproperty uchar blue\n"
        b"element face 2\nproperty list uchar int vertex_indices\nend_header\n"
        b"0 0 0 255 0 0\n1 0 0 0 255 0\n1 1 0 0 0 255\n0 1 0 9 9 9\n0.5 0.5 1 1 2 3\n"
        b"4 0 1 2 3\n3 0 1 4\n")
    be = (b"ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty float x\n"
          b"property float y\nproperty float z\nproperty float nx\nproperty float ny\n"
          b"property float nz\nelement face 1\nproperty list uchar int vertex_indices\n"
          b"property uchar flags\nelement material 1\nproperty int id\nend_header\n")
    for v in [(0, 0, 2), (1, 0, 2), (0, 1, 2)]:
        be += struct.pack(">6f", *v, 0, 0, -1)
    be += struct.pack(">B3iB", 3, 0, 1, 2, 7) + struct.pack(">i", 5)
    put("ply", "big_endian_normals.ply", be)

    # --- iPhone depth.bin (iphone_depth_fuzz: byte 0 even = one record's payload, odd = a
    # whole-file raw-deflate stream; byte 1 % 4 = the frame index there). Raw deflate of
    # float32 metres (one record; two frames as a whole file) and a hand-built LZ4 block of
    # uint16 mm (two literal bytes = 1000 mm, one match at offset 2, 16 final literals).
    ramp = (np.arange(256 * 192, dtype=np.float32) % 5000) / 1000
    def raw_deflate(b):
        z = zlib.compressobj(6, zlib.DEFLATED, -15)
        return z.compress(b) + z.flush()
    put("iphone_depth", "record_deflate", b"\x00\x00" + raw_deflate(ramp.tobytes()))
    put("iphone_depth", "file_deflate_frame1", b"\x01\x01" +
        raw_deflate(ramp.tobytes() + (ramp[::-1] * 2).tobytes()))
    match = 256 * 192 * 2 - 2 - 16
    lz4 = (bytes([0x2F]) + b"\xe8\x03" + struct.pack("<H", 2) +
           b"\xff" * ((match - 4 - 15) // 255) + bytes([(match - 4 - 15) % 255]) +
           bytes([0xF0, 1]) + b"\xe8\x03" * 8)
    put("iphone_depth", "record_lz4", b"\x00\x00" + lz4)

    # --- Pickles (pickle_fuzz): a LoFTR-style MegaDepth scene_info dict with NumPy object
    # arrays, numeric arrays and scalars, at protocols 2, 4 and 5, and the writer's own form.
    import pickle
    info = {"image_paths": np.array(["Undistorted_SfM/0015/images/a.jpg", None], dtype=object),
            "depth_paths": np.array(["d/a.h5", None], dtype=object),
            "intrinsics": np.array([np.eye(3), None], dtype=object),
            "poses": np.array([np.eye(4), None], dtype=object),
            "pair_infos": np.array([((0, 1), np.float64(0.3), np.zeros((1, 2)))], dtype=object),
            "u": np.array(["ab"]), "f": np.asfortranarray(np.ones((2, 2), ">f4"))}
    for proto in (2, 4, 5):
        put("pickle", f"scene_info_p{proto}", pickle.dumps(info, protocol=proto))
    put("pickle", "plain_list", pickle.dumps({"k": [(1, 2.5, "x"), [None, True]]}, protocol=2))

    # --- gzip members (gzip_fuzz): Python's gzip with a file name and mtime, zlib's raw
    # gzip wrapper, an empty member, an .npy as a shard holds it, two members in a row.
    import gzip as gz
    npy_bytes = io.BytesIO()
    np.save(npy_bytes, np.arange(300, dtype=np.float32).reshape(15, 20))
    put("gzip", "npy", gz.compress(npy_bytes.getvalue(), 1, mtime=0))
    with io.BytesIO() as b:
        with gz.GzipFile("label01.npy", "wb", 6, b, mtime=12345) as f:
            f.write(bytes(range(256)) * 8)
        put("gzip", "named", b.getvalue())
    z = zlib.compressobj(9, zlib.DEFLATED, 31)
    put("gzip", "zlib_wrapper", z.compress(b"abc" * 1000) + z.flush())
    put("gzip", "empty", gz.compress(b"", mtime=0))
    put("gzip", "two_members", gz.compress(b"x", mtime=0) + gz.compress(b"y", mtime=0))

    # --- stored pair samples (sample_check_fuzz: records of name, size, bytes): a small
    # sample consistent with its json (every check passes), with occupancy words and a PNG,
    # and variants without images or occupancy.
    for tag, sample in PairSamples():
        put("sample_check", tag, b"".join(
            bytes([len(name)]) + name.encode() + struct.pack("<I", len(data)) + data
            for name, data in sample))

    # --- stored N-view samples, the same records (views_sample_check.h): a 2-view sample
    # consistent with its json, with tracks in every state but NO_DEPTH, and one without images.
    for tag, sample in ViewsSamples():
        put("sample_check", tag, b"".join(
            bytes([len(name)]) + name.encode() + struct.pack("<I", len(data)) + data
            for name, data in sample))

    for target, n in sorted(counts.items()):
        print(f"make_seeds.py: {target}: {n} seeds")


def PairSamples():
    """Small pair samples as `occgt build` stores them, consistent with their json: 16x12
    pixels, stride 4, one vv match, occupancy words of 4 bins, a PNG of each image."""
    import json

    w, h, s, bins = 16, 12, 4, 4
    names = ["NO_DEPTH", "OUT_OF_VIEW", "VISIBLE", "OCCLUDED", "INCONSISTENT", "UNKNOWN"]
    label = np.ones((h, w), np.uint8)  # OUT_OF_VIEW
    label[:, :8] = 2  # VISIBLE
    label[0, 15] = 0  # NO_DEPTH where the depth is 0
    depth = np.full((h, w), 2.0, np.float32)
    depth[0, 15] = 0

    def npy(a):
        b = io.BytesIO()
        np.save(b, a)
        return b.getvalue()

    def metrics(lab, stride):
        g = lab[::stride, ::stride]
        c = {n: int((g == k).sum()) for k, n in enumerate(names)}
        sampled = int(g.size)
        valid = sampled - c["NO_DEPTH"]
        vis, occ = c["VISIBLE"], c["OCCLUDED"]
        seen = vis + occ + c["INCONSISTENT"] + c["UNKNOWN"]
        return {"sampled": sampled, "valid": valid, "counts": c,
                "overlap": seen / valid if valid else 0.0,
                "consistent_overlap": vis / sampled, "occlusion_ratio": occ / sampled,
                "occlusion_ratio_visible": occ / (vis + occ) if vis + occ else 0.0}

    cells = label[s // 2::s, s // 2::s][:h // s, :w // s].copy()
    # One vv match: cell 0 of image 0 (anchor (2, 2), VISIBLE) to cell 0 of image 1.
    matches = np.array([[0, 0]], np.int32)
    match_type = np.zeros(1, np.uint8)
    match_xy = np.array([[2.0, 2.0]], np.float32)
    occ = np.zeros((h // 2, w // 2), np.uint64)
    known = np.full((h // 2, w // 2), 0b0111, np.uint64)
    occ[0, 0] = 0b0100
    K = [[20.0, 0.0, 7.5], [0.0, 20.0, 5.5], [0.0, 0.0, 1.0]]
    eye = np.eye(4).tolist()
    png = io.BytesIO()
    Image.fromarray(np.zeros((h, w, 3), np.uint8)).save(png, format="PNG")
    occupied, known_bits = 1, 3 * (h // 2) * (w // 2)
    meta = {
        "key": "s/0_1", "scene": "s", "frame0": {"id": "0", "number": 0},
        "frame1": {"id": "1", "number": 1}, "resolution": [w, h], "K0": K, "K1": K,
        "world_from_cam0": eye, "world_from_cam1": eye, "T_0to1": eye,
        "metrics": {"01": metrics(label, 1), "10": metrics(label, 1)},
        "score_metrics": {"01": metrics(label, 2), "10": metrics(label, 2)},
        "matches": {"total": 1, "vv": 1, "vo": 0, "ov": 0}, "score_stride": 2,
        "label_options": {"min_depth_m": 0.1, "max_depth_m": 10.0},
        "patch_options": {"stride": s, "anchor": "center", "mutual": True},
        "occupancy": {"bins": {"edges_m": [0.1, 1.0, 2.0, 3.0, 4.0]}, "encoding": "packed",
                      "grid": [w // 2, h // 2],
                      "counts0": {"occupied": occupied, "free": known_bits - occupied,
                                  "unknown": bins * (h // 2) * (w // 2) - known_bits},
                      "counts1": {"occupied": occupied, "free": known_bits - occupied,
                                  "unknown": bins * (h // 2) * (w // 2) - known_bits}},
        "image": {"format": "png"}}
    members = [("label01.npy", npy(label)), ("label10.npy", npy(label)),
               ("matches.npy", npy(matches)), ("match_type.npy", npy(match_type)),
               ("match_xy.npy", npy(match_xy)), ("cells0.npy", npy(cells)),
               ("cells1.npy", npy(cells)), ("occ0.npy", npy(occ)), ("known0.npy", npy(known)),
               ("occ1.npy", npy(occ)), ("known1.npy", npy(known)),
               ("image0.png", png.getvalue()), ("image1.png", png.getvalue()),
               ("depth0.npy", npy(depth)), ("depth1.npy", npy(depth))]
    yield "full", [("json", json.dumps(meta).encode())] + members
    bare = dict(meta, occupancy=None, image=None)
    yield "bare", [("json", json.dumps(bare).encode())] + [
        m for m in members if not m[0].startswith(("occ", "known", "image"))]


def ViewsSamples():
    """Small N-view samples as `occgt tuples --shards` stores them, consistent with their json:
    2 views of 8x6 pixels; view 0's left half VISIBLE in view 1, one pixel OCCLUDED there;
    num_tracks above the valid pixels, so the queries are all of view 0's valid pixels."""
    import json

    w, h, n = 8, 6, 2
    depth = np.full((h, w), 2.0, np.float32)
    depth[0, 7] = 0  # invalid
    valid = np.stack([(depth > 0).astype(np.uint8)] * n)
    vis = np.zeros((n, h, w), np.uint32)
    occ = np.zeros((n, h, w), np.uint32)
    for i in range(n):
        vis[i][valid[i] == 1] |= np.uint32(1 << i)
    vis[0][:, :4] |= np.uint32(2)
    occ[0][2, 5] = 2
    queries = np.array([[u, v] for v in range(h) for u in range(w) if valid[0, v, u]], np.int32)
    q = len(queries)
    xy = np.full((n, q, 2), np.nan, np.float32)
    track_depth = np.full((n, q), np.nan, np.float32)
    state = np.full((n, q), 2, np.uint8)  # OUT_OF_VIEW
    for k, (u, v) in enumerate(queries):
        xy[0, k] = (u, v)
        track_depth[0, k] = depth[v, u]
        state[0, k] = 0
        if vis[0, v, u] & 2 or occ[0, v, u] & 2:
            xy[1, k] = (u + 0.5, v)
            track_depth[1, k] = 2.0
            state[1, k] = 0 if vis[0, v, u] & 2 else 1
    visible = sum(bin(int(x) & ~(1 << i)).count("1") for i in range(n) for x in vis[i].ravel())
    occluded = int(sum(bin(int(x)).count("1") for x in occ.ravel()))

    def npy(a):
        b = io.BytesIO()
        np.save(b, a)
        return b.getvalue()

    K = [[10.0, 0.0, 3.5], [0.0, 10.0, 2.5], [0.0, 0.0, 1.0]]
    poses = [np.eye(4).tolist(), np.eye(4).tolist()]
    poses[1][0][3] = 0.25
    png = io.BytesIO()
    Image.fromarray(np.zeros((h, w, 3), np.uint8)).save(png, format="PNG")
    meta = {
        "kind": "occgt-views-sample", "key": "s/tuple_000000", "scene": "s", "tuple_index": 0,
        "num_views": n, "frames": [{"id": "a", "number": 0}, {"id": "b", "number": 1}],
        "resolution": [w, h], "K": [K, K], "world_from_cam": poses,
        "covisibility": [[1.0, 0.5], [0.5, 1.0]],
        "label_options": {"min_depth_m": 0.0, "max_depth_m": 10.0},
        "tracks": {"num_tracks": 64, "query_view": 0, "seed": 0, "count": q},
        "metrics": {"counts": {"VISIBLE": visible, "OCCLUDED": occluded},
                    "valid": int(valid.sum()),
                    "occlusion_ratio_visible": occluded / (visible + occluded)},
        "image": {"format": "png", "K": [K, K]}, "compression": "none",
        "options_digest": "0" * 32, "recipe": "r", "split": "s"}
    members = [("depth0.npy", npy(depth)), ("depth1.npy", npy(depth)),
               ("intrinsics.npy", npy(np.array([K, K]))),
               ("world_from_cam.npy", npy(np.array(poses))), ("visible_in.npy", npy(vis)),
               ("occluded_in.npy", npy(occ)), ("valid.npy", npy(valid)),
               ("queries.npy", npy(queries)), ("track_xy.npy", npy(xy)),
               ("track_depth.npy", npy(track_depth)), ("track_state.npy", npy(state)),
               ("image0.png", png.getvalue()), ("image1.png", png.getvalue())]
    yield "views", [("json", json.dumps(meta).encode())] + members
    bare = dict(meta, image=None)
    yield "views_bare", [("json", json.dumps(bare).encode())] + [
        m for m in members if not m[0].startswith("image")]


def Exr(channels, width, height):
    """A minimal single-part scanline OpenEXR 2.0 file, FLOAT channels, no compression."""
    def attr(name, type_name, value):
        return name.encode() + b"\0" + type_name.encode() + b"\0" + struct.pack("<i", len(value)) + value
    chlist = b"".join(c.encode() + b"\0" + struct.pack("<iB3xii", 2, 0, 1, 1)
                      for c in sorted(channels)) + b"\0"
    box = struct.pack("<iiii", 0, 0, width - 1, height - 1)
    header = (attr("channels", "chlist", chlist) + attr("compression", "compression", b"\0") +
              attr("dataWindow", "box2i", box) + attr("displayWindow", "box2i", box) +
              attr("lineOrder", "lineOrder", b"\0") +
              attr("pixelAspectRatio", "float", struct.pack("<f", 1.0)) +
              attr("screenWindowCenter", "v2f", struct.pack("<ff", 0, 0)) +
              attr("screenWindowWidth", "float", struct.pack("<f", 1.0)) + b"\0")
    start = 8 + len(header) + 8 * height
    lines, offsets = b"", []
    for y in range(height):
        offsets.append(start + len(lines))
        data = b"".join(struct.pack("<f", 1.0 + y + 0.25 * x + c)
                        for c in range(len(channels)) for x in range(width))
        lines += struct.pack("<ii", y, len(data)) + data
    return (struct.pack("<ii", 20000630, 2) + header +
            b"".join(struct.pack("<Q", o) for o in offsets) + lines)


if __name__ == "__main__":
    main()
