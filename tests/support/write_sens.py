"""Writes ScanNet .sens files (docs/DATASETS.md "ScanNet raw .sens") for the tests, and the
same frames in the Python exporter's layout (color/, depth/, pose/, intrinsic/), so that a
test can read one scene both ways. ScanNet's own files may not be redistributed: the tests
write their own (a synthetic scene, and the real 7-Scenes sample frames re-packed).

Run with Debian's /usr/bin/python3 (numpy, cv2, zlib). As a module: write_sens(path, ...)
and write_export(folder, ...); as a script:
    write_sens.py synthetic OUT         OUT/sens/synth/synth.sens + OUT/export/synth/
    write_sens.py sevenscenes SRC OUT   the 7-Scenes sample SRC, as OUT/sens/seven/seven.sens
                                        + OUT/export/seven/
"""
import glob
import os
import struct
import sys
import zlib

import cv2
import numpy as np

COLOR_RAW, COLOR_PNG, COLOR_JPEG = 0, 1, 2
DEPTH_RAW, DEPTH_ZLIB = 0, 1


def mat4(K):
    m = np.eye(4, dtype=np.float32)
    m[:3, :3] = np.asarray(K, dtype=np.float32)
    return m


def header_bytes(K_color, K_depth, color_size, depth_size, n_frames, color_compression=COLOR_JPEG,
                 depth_compression=DEPTH_ZLIB, depth_shift=1000.0, sensor=b"StructureSensor",
                 version=4):
    out = struct.pack("<I", version) + struct.pack("<Q", len(sensor)) + sensor
    for m in [mat4(K_color), np.eye(4, dtype=np.float32), mat4(K_depth), np.eye(4, dtype=np.float32)]:
        out += np.asarray(m, dtype="<f4").tobytes()
    out += struct.pack("<iiIIIIfQ", color_compression, depth_compression, color_size[0],
                       color_size[1], depth_size[0], depth_size[1], depth_shift, n_frames)
    return out


def frame_bytes(pose, color_payload, depth_payload):
    return (np.asarray(pose, dtype="<f4").tobytes() + struct.pack("<QQQQ", 0, 0, len(color_payload),
                                                                   len(depth_payload)) +
            color_payload + depth_payload)


def write_sens(path, frames, K_color, K_depth, color_size, depth_size, color_compression=COLOR_JPEG,
               depth_compression=DEPTH_ZLIB, depth_shift=1000.0):
    """frames: list of (pose float32 4x4, colour payload bytes, depth uint16 [H, W])."""
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "wb") as f:
        f.write(header_bytes(K_color, K_depth, color_size, depth_size, len(frames), color_compression,
                             depth_compression, depth_shift))
        for pose, color, depth in frames:
            raw = np.ascontiguousarray(depth, dtype="<u2").tobytes()
            payload = zlib.compress(raw, 1) if depth_compression == DEPTH_ZLIB else raw
            f.write(frame_bytes(pose, color, payload))
        f.write(struct.pack("<Q", 0))  # numIMU


def write_matrix(path, m):
    # %.17g of the float32 values: the text parses back to the very doubles the .sens gives.
    with open(path, "w") as f:
        for row in np.asarray(m, dtype=np.float32).astype(np.float64):
            f.write(" ".join("%.17g" % v for v in row) + "\n")


def write_export(folder, frames, K_color, K_depth, color_ext):
    """The Python exporter's layout of the same frames (colour payloads as files)."""
    for sub in ["color", "depth", "pose", "intrinsic"]:
        os.makedirs(os.path.join(folder, sub), exist_ok=True)
    write_matrix(os.path.join(folder, "intrinsic", "intrinsic_color.txt"), mat4(K_color))
    write_matrix(os.path.join(folder, "intrinsic", "intrinsic_depth.txt"), mat4(K_depth))
    for i, (pose, color, depth) in enumerate(frames):
        with open(os.path.join(folder, "color", f"{i}{color_ext}"), "wb") as f:
            f.write(color)
        assert cv2.imwrite(os.path.join(folder, "depth", f"{i}.png"), depth.astype(np.uint16))
        with open(os.path.join(folder, "pose", f"{i}.txt"), "w") as f:
            for row in np.asarray(pose, dtype=np.float32).astype(np.float64):
                f.write(" ".join("-inf" if np.isneginf(v) else "%.17g" % v for v in row) + "\n")


def synthetic_frames(depth_size=(80, 60), color_size=(160, 120)):
    """A camera moving sideways in front of a tilted plane with a box; frame 2 lost tracking."""
    w, h = depth_size
    K_depth = np.array([[70.0, 0, 39.5], [0, 70.0, 29.5], [0, 0, 1]])
    K_color = np.array([[140.0, 0, 79.5], [0, 140.0, 59.5], [0, 0, 1]])
    u, v = np.meshgrid(np.arange(w), np.arange(h))
    frames = []
    rng = np.random.default_rng(7)
    for i in range(5):
        pose = np.eye(4, dtype=np.float32)
        pose[0, 3] = 0.05 * i
        if i == 2:
            pose[:] = -np.inf
        depth_m = 2.0 + 0.01 * v + 0.004 * u
        box = (abs(u - (40 - 4 * i)) < 10) & (abs(v - 30) < 12)
        depth_m[box] = 1.2
        depth = np.round(depth_m * 1000).astype(np.uint16)
        depth[0:3, 0:3] = 0  # missing values
        img = rng.integers(0, 255, (color_size[1], color_size[0], 3), dtype=np.uint8)
        ok, jpg = cv2.imencode(".jpg", img)
        assert ok
        frames.append((pose, jpg.tobytes(), depth))
    return frames, K_color, K_depth, color_size, depth_size


def sevenscenes_frames(src):
    """The 7-Scenes sample frames (colour PNG 640x480, depth uint16 mm, pose text)."""
    K = np.loadtxt(os.path.join(src, "camera-intrinsics.txt"))
    frames = []
    for pose_path in sorted(glob.glob(os.path.join(src, "rgbd-frames", "frame-*.pose.txt"))):
        base = pose_path[: -len(".pose.txt")]
        pose = np.loadtxt(pose_path).astype(np.float32)
        depth = cv2.imread(base + ".depth.png", cv2.IMREAD_UNCHANGED)
        assert depth is not None and depth.dtype == np.uint16, base
        with open(base + ".color.png", "rb") as f:
            color = f.read()
        frames.append((pose, color, depth))
    h, w = frames[0][2].shape
    return frames, K, K, (640, 480), (w, h)


def main(argv):
    if len(argv) == 3 and argv[1] == "synthetic":
        frames, Kc, Kd, cs, ds = synthetic_frames()
        write_sens(os.path.join(argv[2], "sens", "synth", "synth.sens"), frames, Kc, Kd, cs, ds)
        write_export(os.path.join(argv[2], "export", "synth"), frames, Kc, Kd, ".jpg")
    elif len(argv) == 4 and argv[1] == "sevenscenes":
        frames, Kc, Kd, cs, ds = sevenscenes_frames(argv[2])
        write_sens(os.path.join(argv[3], "sens", "seven", "seven.sens"), frames, Kc, Kd, cs, ds,
                   color_compression=COLOR_PNG)
        write_export(os.path.join(argv[3], "export", "seven"), frames, Kc, Kd, ".png")
    else:
        sys.exit(__doc__)


if __name__ == "__main__":
    main(sys.argv)
