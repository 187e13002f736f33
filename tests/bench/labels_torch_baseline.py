#!/usr/bin/python3
"""Times the tensor formulation of pixel labels in real PyTorch on CPU, one thread.

The scene and the op list are those of BM_BatchedBaseline in tests/bench/labels_bench.cc:
LoFTR's warp_kpts (unproject with K0^-1, R @ + t, K1 @, divide, bounds, .long(), gather of
the target depth, depth test), written for every pixel of a 640x480 image and extended to
the six labels and counts of occgt's `default` preset (GROUND_TRUTH.md §2), in eager mode
with batch size 1 as a trainer runs it. Not a test: docs/PERFORMANCE.md quotes its median
next to the C++ figures, measured in the same session.

    /usr/bin/python3 tests/bench/labels_torch_baseline.py [--repetitions 10] [--iterations 20]

Needs python3-torch (Debian) and python3-numpy.
"""
import argparse
import math
import statistics
import time

import numpy as np
import torch

W, H = 640, 480
F, CX, CY = 500.0, 319.5, 239.5
# PixelLabel codes (libgt/geometry/labels.h)
NO_DEPTH, OUT_OF_VIEW, VISIBLE, OCCLUDED, INCONSISTENT, UNKNOWN = range(6)
# `default` preset
MIN_DEPTH, MAX_DEPTH, ABS_TOL, REL_TOL, EPS = 0.0, 1000.0, 0.1, 0.05, 0.0


def yaw(deg):
    a = math.radians(deg)
    return np.array([[math.cos(a), 0, math.sin(a)], [0, 1, 0], [-math.sin(a), 0, math.cos(a)]])


def render(rects, world_from_cam):
    """Planar depth of axis-aligned rectangles (axis, at, lo[2], hi[2]), 0 where none."""
    rot, origin = world_from_cam
    u, v = np.meshgrid(np.arange(W, dtype=np.float64), np.arange(H, dtype=np.float64))
    ray = np.stack([(u - CX) / F, (v - CY) / F, np.ones_like(u)], axis=-1)  # z = 1 in cam
    d = ray @ rot.T
    best = np.full((H, W), np.inf)
    for axis, at, lo, hi in rects:
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (at - origin[axis]) / d[..., axis]
        p = origin + t[..., None] * d
        others = [a for a in range(3) if a != axis]
        inside = (t > 1e-9) & (t < best)
        for j, a in enumerate(others):
            inside &= (p[..., a] >= lo[j]) & (p[..., a] <= hi[j])
        best = np.where(inside, t, best)
    return np.where(np.isfinite(best), best, 0.0).astype(np.float32)


def scene():
    rects = [(2, 5.0, (-1e9, -1e9), (1e9, 1e9)), (2, 2.5, (-0.5, -0.4), (0.5, 0.4)),
             (0, 0.5, (-0.4, 2.5), (0.4, 3.2))]
    world_from_b = (yaw(-9.0), np.array([0.9, 0.1, -0.2]))
    depth_a = render(rects, (np.eye(3), np.zeros(3)))
    depth_b = render(rects, world_from_b)
    b_from_a = np.eye(4)
    b_from_a[:3, :3] = world_from_b[0].T
    b_from_a[:3, 3] = -world_from_b[0].T @ world_from_b[1]
    k = np.array([[F, 0, CX], [0, F, CY], [0, 0, 1]])
    as_t = lambda a: torch.from_numpy(np.ascontiguousarray(a)).float()[None]
    return as_t(depth_a), as_t(depth_b), as_t(b_from_a[:3]), as_t(k), as_t(k)


def valid_depth(d):
    return torch.isfinite(d) * (d > 0) * (d >= MIN_DEPTH) * (d <= MAX_DEPTH)


@torch.no_grad()
def labels_and_counts(kpts0, depth0, depth1, t_0to1, k0, k1):
    """LoFTR's warp_kpts op by op, with occgt's `default` decisions and the counts."""
    h, w = depth1.shape[1:3]
    kpts0_long = kpts0.round().long()
    kpts0_depth = torch.stack(
        [depth0[i, kpts0_long[i, :, 1], kpts0_long[i, :, 0]] for i in range(kpts0.shape[0])])
    valid_mask = valid_depth(kpts0_depth)
    kpts0_h = torch.cat([kpts0, torch.ones_like(kpts0[:, :, [0]])], dim=-1) * kpts0_depth[..., None]
    kpts0_cam = k0.inverse() @ kpts0_h.transpose(2, 1)
    w_kpts0_cam = t_0to1[:, :3, :3] @ kpts0_cam + t_0to1[:, :3, [3]]
    z = w_kpts0_cam[:, 2, :]
    w_kpts0_h = (k1 @ w_kpts0_cam).transpose(2, 1)
    w_kpts0 = w_kpts0_h[:, :, :2] / (w_kpts0_h[:, :, [2]] + EPS)
    in_front = z > MIN_DEPTH
    covisible_mask = (w_kpts0[:, :, 0] >= -0.5) * (w_kpts0[:, :, 0] < w - 0.5) * \
        (w_kpts0[:, :, 1] >= -0.5) * (w_kpts0[:, :, 1] < h - 0.5) * in_front * valid_mask
    w_kpts0_long = (w_kpts0 + 0.5).floor().long()
    w_kpts0_long[~covisible_mask, :] = 0
    w_kpts0_depth = torch.stack(
        [depth1[i, w_kpts0_long[i, :, 1], w_kpts0_long[i, :, 0]] for i in range(kpts0.shape[0])])
    known_mask = valid_depth(w_kpts0_depth)
    tol = (REL_TOL * z).clamp(min=ABS_TOL)
    diff = z - w_kpts0_depth
    labels = torch.full_like(kpts0_depth, INCONSISTENT, dtype=torch.uint8)
    labels = torch.where(diff > tol, OCCLUDED, labels)
    labels = torch.where(diff.abs() <= tol, VISIBLE, labels)
    labels = torch.where(known_mask, labels, UNKNOWN)
    labels = torch.where(covisible_mask, labels, OUT_OF_VIEW)
    labels = torch.where(valid_mask, labels, NO_DEPTH).to(torch.uint8)
    counts = torch.bincount(labels.flatten(), minlength=6)
    return labels, w_kpts0, counts


def grid():
    """create_meshgrid(H, W) in pixels, as a [1, L, 2] (x, y) tensor, built per call."""
    ys, xs = torch.meshgrid(torch.arange(H, dtype=torch.float32),
                            torch.arange(W, dtype=torch.float32), indexing="ij")
    return torch.stack([xs, ys], dim=-1).reshape(1, -1, 2)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repetitions", type=int, default=10)
    ap.add_argument("--iterations", type=int, default=20, help="calls per repetition")
    args = ap.parse_args()
    torch.set_num_threads(1)
    depth0, depth1, t_0to1, k0, k1 = scene()
    _, _, counts = labels_and_counts(grid(), depth0, depth1, t_0to1, k0, k1)
    wall, cpu = [], []
    for _ in range(args.repetitions):
        w0, c0 = time.perf_counter(), time.process_time()
        for _ in range(args.iterations):
            labels_and_counts(grid(), depth0, depth1, t_0to1, k0, k1)
        wall.append((time.perf_counter() - w0) / args.iterations * 1e3)
        cpu.append((time.process_time() - c0) / args.iterations * 1e3)
    print(f"torch {torch.__version__}, threads {torch.get_num_threads()}, {W}x{H}, "
          f"{args.repetitions} repetitions of {args.iterations} calls")
    print("counts (NO_DEPTH, OUT_OF_VIEW, VISIBLE, OCCLUDED, INCONSISTENT, UNKNOWN):",
          counts.tolist())
    print(f"torch_labels_and_counts  median CPU {statistics.median(cpu):.3f} ms  "
          f"median wall {statistics.median(wall):.3f} ms")


if __name__ == "__main__":
    main()
