"""A straightforward reference of the evaluation protocol (GROUND_TRUTH.md §7), written
from its text with NumPy and OpenCV's Python binding, to check libgt/eval against.
Slow and simple on purpose: one pair at a time, no shortcuts."""
from typing import List, Optional, Sequence, Tuple

import cv2
import numpy as np


def estimate_pose(kpts0: np.ndarray, kpts1: np.ndarray, K0: np.ndarray, K1: np.ndarray,
                  thresh_px: float, conf: float) -> Optional[Tuple[np.ndarray, np.ndarray]]:
    """(R, t) of cam1_from_cam0, or None (< 5 matches, no E, no block with an inlier)."""
    if len(kpts0) < 5:
        return None
    thr = thresh_px / np.mean([K0[0, 0], K1[1, 1], K0[0, 0], K1[1, 1]])
    p0 = (kpts0.astype(np.float64) - K0[[0, 1], [2, 2]][None]) / K0[[0, 1], [0, 1]][None]
    p1 = (kpts1.astype(np.float64) - K1[[0, 1], [2, 2]][None]) / K1[[0, 1], [0, 1]][None]
    E, mask = cv2.findEssentialMat(p0, p1, np.eye(3), threshold=thr, prob=conf,
                                   method=cv2.RANSAC)
    if E is None:
        return None
    best, best_n = None, 0
    for block in np.split(E, len(E) / 3):
        n, R, t, _ = cv2.recoverPose(block, p0, p1, np.eye(3), 1e9, mask=mask)
        if n > best_n:
            best, best_n = (R, t[:, 0]), n
    return best


def pose_error(T_0to1: np.ndarray, R: np.ndarray, t: np.ndarray) -> float:
    """max(rotation error, folded translation angle) in degrees."""
    t_gt = T_0to1[:3, 3]
    cos_t = np.dot(t, t_gt) / (np.linalg.norm(t) * np.linalg.norm(t_gt))
    t_err = np.rad2deg(np.arccos(np.clip(cos_t, -1.0, 1.0)))
    t_err = min(t_err, 180.0 - t_err)
    cos_r = (np.trace(R.T @ T_0to1[:3, :3]) - 1) / 2
    r_err = np.rad2deg(np.arccos(np.clip(cos_r, -1.0, 1.0)))
    return float(max(t_err, r_err))


def auc(errors: Sequence[float], thresholds: Sequence[float]) -> List[float]:
    """Sort, prepend 0 to errors and recall, trapezoid up to each threshold, / threshold."""
    errs = [0.0] + sorted(errors)
    recall = list(np.linspace(0, 1, len(errs)))
    out = []
    for thr in thresholds:
        last = int(np.searchsorted(errs, thr))
        y = recall[:last] + [recall[last - 1]]
        x = errs[:last] + [thr]
        out.append(float(np.trapz(y, x) / thr))
    return out


def epipolar_precision(kpts0, kpts1, K0, K1, T_0to1, thr: float) -> float:
    """Share of matches whose symmetric epipolar distance (normalised) is below thr."""
    if len(kpts0) == 0:
        return 0.0
    t = T_0to1[:3, 3]
    tx = np.array([[0, -t[2], t[1]], [t[2], 0, -t[0]], [-t[1], t[0], 0]])
    E = tx @ T_0to1[:3, :3]
    p0 = np.c_[(kpts0 - K0[[0, 1], [2, 2]]) / K0[[0, 1], [0, 1]], np.ones(len(kpts0))]
    p1 = np.c_[(kpts1 - K1[[0, 1], [2, 2]]) / K1[[0, 1], [0, 1]], np.ones(len(kpts1))]
    Ep0 = p0 @ E.T
    Etp1 = p1 @ E
    num = np.sum(p1 * Ep0, -1) ** 2
    d = num * (1 / (Ep0[:, 0] ** 2 + Ep0[:, 1] ** 2) + 1 / (Etp1[:, 0] ** 2 + Etp1[:, 1] ** 2))
    return float(np.mean(d < thr))
