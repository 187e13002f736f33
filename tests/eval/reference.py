"""A straightforward reference of the evaluation protocol (GROUND_TRUTH.md §7), written
from its text with NumPy and OpenCV's Python binding, to check libgt/eval against.
Slow and simple on purpose: one pair at a time, no shortcuts."""
from typing import List, Optional, Sequence, Tuple

import cv2
import numpy as np


METHODS = {"ransac": cv2.RANSAC, "lmeds": cv2.LMEDS, "usac_default": cv2.USAC_DEFAULT,
           "usac_accurate": cv2.USAC_ACCURATE, "usac_magsac": cv2.USAC_MAGSAC,
           "usac_prosac": cv2.USAC_PROSAC}


def estimate_pose(kpts0: np.ndarray, kpts1: np.ndarray, K0: np.ndarray, K1: np.ndarray,
                  thresh_px: float, conf: float, method: str = "ransac", max_iters: int = 1000,
                  focal_mean: str = "loftr", confidence: Optional[np.ndarray] = None
                  ) -> Optional[Tuple[np.ndarray, np.ndarray]]:
    """(R, t) of cam1_from_cam0, or None (< 5 matches, no E, no block with an inlier).
    method: a cv::findEssentialMat method (docs/EVAL.md); usac_prosac takes the matches
    sorted by decreasing `confidence` (stable). focal_mean: "loftr" divides the pixel
    threshold by mean(K0 fx, K1 fy, K0 fx, K1 fy), "all" by mean(fx, fy of both)."""
    if len(kpts0) < 5:
        return None
    if focal_mean == "loftr":
        f = np.mean([K0[0, 0], K1[1, 1], K0[0, 0], K1[1, 1]])
    else:
        f = np.mean([K0[0, 0], K0[1, 1], K1[0, 0], K1[1, 1]])
    thr = thresh_px / f
    p0 = (kpts0.astype(np.float64) - K0[[0, 1], [2, 2]][None]) / K0[[0, 1], [0, 1]][None]
    p1 = (kpts1.astype(np.float64) - K1[[0, 1], [2, 2]][None]) / K1[[0, 1], [0, 1]][None]
    if method == "usac_prosac":
        order = np.argsort(-np.asarray(confidence), kind="stable")
        p0, p1 = p0[order], p1[order]
    E, mask = cv2.findEssentialMat(p0, p1, np.eye(3), method=METHODS[method], prob=conf,
                                   threshold=thr, maxIters=max_iters)
    if E is None:
        return None
    best, best_n = None, 0
    for block in np.split(E, len(E) / 3):
        # LoFTR's line as written: this overload has no distanceThresh (the 1e9 goes to
        # its R output), so OpenCV's default of 50 applies (docs/EVAL.md).
        n, R, t, _ = cv2.recoverPose(block, p0, p1, np.eye(3), 1e9, mask=mask)
        if n > best_n:
            best, best_n = (R, t[:, 0]), n
    return best


def best_of_sweep(mean_auc: Sequence[float], groups: Sequence[Sequence[int]]) -> int:
    """glue-factory's choice (gluefactory/eval/utils.py eval_poses, eval_pipeline.py
    run_eval): per group max() over a dict in threshold order (first maximum wins), then
    a dict keyed by the mean AUC (the last group with the maximum wins)."""
    best_by_value = {}
    for g in groups:
        per_th = {i: mean_auc[i] for i in g}
        b = max(per_th, key=per_th.get)
        best_by_value[per_th[b]] = b
    return best_by_value[max(best_by_value)]


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
