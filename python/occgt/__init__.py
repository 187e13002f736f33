"""occgt: ground truth for occlusion-aware image matching, from Python.

The numerics are occgt's C++ library (the extension module ``occgt._occgt``, pybind11); this
package adds type hints and documentation. Conventions (docs/GROUND_TRUTH.md and ../shared/design/GROUND_TRUTH.md §1): OpenCV camera
axes (x right, y down, z forward), depth = planar z in metres (0, NaN, inf = invalid), pixel
(u, v) = column u, row v with its centre at the continuous point (u, v), poses
``world_from_cam`` (camera to world, 4x4, metres), images [height, width].

Functions:
    pair_ground_truth  labels, metrics, patch matches (and occupancy) of one pair of frames,
                       the same arrays as ``occgt pair`` / ``occgt occupancy`` write
    dense_volume       occupancy words -> uint8 [bins, H/2, W/2] (0 free, 1 occupied, 255 unknown)
    open_dataset       occgt's dataset readers: scenes, frames, frames at a working resolution
    pair_from_scene    pair_ground_truth of two frames of a scene, as ``occgt pair`` computes it
    views_ground_truth N views (N <= 32): per-pixel visibility of every view in every other
                       view as bitmasks, and tracks of query pixels with a state per view
    views_seen_by      seen_by and its histogram of stored bitmasks (an N-view shard's)
    load_mesh          a triangle mesh (PLY) and its ray-casting BVH, built once
    render_depth       planar depth of a mesh seen by a pinhole, OpenCV or OpenCV-fisheye camera

Bad arguments raise ValueError naming the argument (``"depth0: expected ..."``). The work runs
without the GIL, so threads calling these functions run in parallel. Docs: docs/PYTHON.md.
"""
from __future__ import annotations

import os
from typing import Any, Dict, Optional, Sequence, Tuple, TypedDict, Union

import numpy as np
import numpy.typing as npt

from . import _occgt
from ._occgt import (FORMATS, LABEL_NAMES, MATCH_TYPE_NAMES, PRESETS, TRACK_STATE_NAMES, Dataset,
                     Frame, Mesh, Scene, ScopeMap)

__version__: str = _occgt.__version__

#: The value each keyword argument of pair_ground_truth takes by default, from the C++ Options
#: structs (truth::ResolvePairTruthOptions of default settings): the signatures below show
#: them, none is written in Python.
PAIR_DEFAULTS: Dict[str, Any] = dict(_occgt.PAIR_DEFAULTS)
_D = PAIR_DEFAULTS
#: The same for views_ground_truth's own keywords (num_tracks, query_view, seed), from
#: truth::ViewsTruthOptions; render_depth's (model, near_m, far_m), from render::RenderOptions;
#: loftr_supervision's (coarse_stride, compat), from truth::LoftrSupervisionOptions; the
#: dataset keywords (device of open_dataset, depth_source of Scene.load, pair_from_scene and
#: PairIndexDataset), from datasets::ReaderOptions and render::FrameDepthOptions.
VIEWS_DEFAULTS: Dict[str, Any] = dict(_occgt.VIEWS_DEFAULTS)
RENDER_DEFAULTS: Dict[str, Any] = dict(_occgt.RENDER_DEFAULTS)
SUPERVISION_DEFAULTS: Dict[str, Any] = dict(_occgt.SUPERVISION_DEFAULTS)
DATASET_DEFAULTS: Dict[str, Any] = dict(_occgt.DATASET_DEFAULTS)

__all__ = [
    "__version__",
    "DATASET_DEFAULTS",
    "FORMATS",
    "LABEL_NAMES",
    "MATCH_TYPE_NAMES",
    "PAIR_DEFAULTS",
    "PRESETS",
    "RENDER_DEFAULTS",
    "SUPERVISION_DEFAULTS",
    "TRACK_STATE_NAMES",
    "VIEWS_DEFAULTS",
    "Dataset",
    "Frame",
    "FusionStats",
    "Mesh",
    "Scene",
    "ScopeMap",
    "LoadedFrame",
    "Metrics",
    "NO_DEPTH",
    "OUT_OF_VIEW",
    "VISIBLE",
    "OCCLUDED",
    "INCONSISTENT",
    "UNKNOWN",
    "VV",
    "VO",
    "OV",
    "PairGroundTruth",
    "dense_volume",
    "depth_at_image_size",
    "load_mesh",
    "open_dataset",
    "pair_from_scene",
    "pair_ground_truth",
    "pair_options",
    "views_ground_truth",
    "views_seen_by",
    "SeenBy",
    "ViewsGroundTruth",
    "TRACK_VISIBLE",
    "TRACK_OCCLUDED",
    "TRACK_OUT_OF_VIEW",
    "TRACK_NO_DEPTH",
    "TRACK_INCONSISTENT",
    "render_depth",
]

#: Label codes (uint8) of label01/label10/cells0/cells1 (LABEL_NAMES[code] is the name):
#: NO_DEPTH the source depth is invalid; OUT_OF_VIEW behind the other camera or outside its
#: image; VISIBLE the other view sees the same surface (within tolerance); OCCLUDED a surface
#: of the other view lies in front of the point; INCONSISTENT the other view sees past it
#: (depth or pose error, motion); UNKNOWN it projects into the other view, which has no depth.
NO_DEPTH: int = LABEL_NAMES.index("NO_DEPTH")
OUT_OF_VIEW: int = LABEL_NAMES.index("OUT_OF_VIEW")
VISIBLE: int = LABEL_NAMES.index("VISIBLE")
OCCLUDED: int = LABEL_NAMES.index("OCCLUDED")
INCONSISTENT: int = LABEL_NAMES.index("INCONSISTENT")
UNKNOWN: int = LABEL_NAMES.index("UNKNOWN")
#: Match type codes (uint8) of match_type (MATCH_TYPE_NAMES[code]): VV visible in both
#: images, VO visible in image 0 and occluded in image 1, OV the reverse.
VV: int = MATCH_TYPE_NAMES.index("vv")
VO: int = MATCH_TYPE_NAMES.index("vo")
OV: int = MATCH_TYPE_NAMES.index("ov")

#: Track state codes (uint8) of views_ground_truth's track_state (TRACK_STATE_NAMES[code]):
#: VISIBLE the view sees the point; OCCLUDED a surface of the view lies in front of it;
#: OUT_OF_VIEW behind the view's camera or outside its image; NO_DEPTH the query pixel has no
#: depth or the view has none where the point lands; INCONSISTENT the view sees past the point.
TRACK_VISIBLE: int = TRACK_STATE_NAMES.index("VISIBLE")
TRACK_OCCLUDED: int = TRACK_STATE_NAMES.index("OCCLUDED")
TRACK_OUT_OF_VIEW: int = TRACK_STATE_NAMES.index("OUT_OF_VIEW")
TRACK_NO_DEPTH: int = TRACK_STATE_NAMES.index("NO_DEPTH")
TRACK_INCONSISTENT: int = TRACK_STATE_NAMES.index("INCONSISTENT")

#: What Scene.load returns: (depth float32 [H, W] metres, K float64 [3, 3], world_from_cam
#: float64 [4, 4]).
LoadedFrame = Tuple[npt.NDArray[np.float32], npt.NDArray[np.float64], npt.NDArray[np.float64]]


class Metrics(TypedDict):
    """Metrics of one direction A->B at stride 1 (docs/GROUND_TRUTH.md §3); the same fields
    and values as ``metrics01``/``metrics10`` of ``occgt pair``'s meta.json."""

    sampled: int  # pixels of A (H * W)
    valid: int  # pixels of A with valid depth
    counts: Dict[str, int]  # per label name (LABEL_NAMES): NO_DEPTH ... UNKNOWN
    overlap: float  # (VISIBLE + OCCLUDED + INCONSISTENT + UNKNOWN) / valid
    consistent_overlap: float  # VISIBLE / sampled
    occlusion_ratio: float  # OCCLUDED / sampled (the paper's)
    occlusion_ratio_visible: float  # OCCLUDED / (VISIBLE + OCCLUDED) (the released code's)


class FusionStats(TypedDict):
    """What happened to the points of the occupancy fusion, summed over the fused frames
    (occupancy::FusionStats; ``fusion.stats`` of ``occgt occupancy``'s occupancy.json). Every
    pixel is counted once: invalid, out of the key range, merged by the downsampling,
    removed as an outlier, or inserted."""

    frames: int  # frames fused
    pixels: int  # width * height summed
    invalid_pixels: int  # dropped: no valid depth (outside [min_depth_m, max_depth_m])
    out_of_key_range: int  # dropped: outside the map's 16-bit key range (beyond max_range_m)
    after_downsample: int  # points left after the downsampling (= valid points when off)
    downsample_fallbacks: int  # frames whose pcl::VoxelGrid would overflow int32
    outliers_removed: int  # dropped by the statistical outlier removal
    inserted_points: int  # points inserted as the end of a ray


class _PairGroundTruthBase(TypedDict):
    label01: npt.NDArray[np.uint8]
    label10: npt.NDArray[np.uint8]
    matches: npt.NDArray[np.int32]
    match_type: npt.NDArray[np.uint8]
    match_xy: npt.NDArray[np.float32]
    cells0: npt.NDArray[np.uint8]
    cells1: npt.NDArray[np.uint8]
    T_0to1: npt.NDArray[np.float64]
    metrics01: Metrics
    metrics10: Metrics
    # The resolved options as a shard sample's json records them: label_options,
    # patch_options, occupancy_options (None without occupancy); pair_options gives the same.
    options: Dict[str, Any]


class PairGroundTruth(_PairGroundTruthBase, total=False):
    """What pair_ground_truth returns; the occupancy keys only with ``occupancy=True``."""

    occ0: npt.NDArray[np.uint64]
    known0: npt.NDArray[np.uint64]
    occ1: npt.NDArray[np.uint64]
    known1: npt.NDArray[np.uint64]
    bin_edges_m: npt.NDArray[np.float64]
    fusion_stats: Optional[FusionStats]  # None for occupancy_mode "two_point"


def pair_ground_truth(
    depth0: npt.ArrayLike,
    depth1: npt.ArrayLike,
    K0: npt.ArrayLike,
    K1: npt.ArrayLike,
    world_from_cam0: npt.ArrayLike,
    world_from_cam1: npt.ArrayLike,
    preset: str = _D["preset"],
    *,
    abs_tol_m: Optional[float] = None,
    rel_tol: Optional[float] = None,
    min_depth_m: Optional[float] = None,
    max_depth_m: Optional[float] = None,
    relative_to: Optional[str] = None,
    bounds: Optional[str] = None,
    target_lookup: Optional[str] = None,
    missing_target: Optional[str] = None,
    stride: int = _D["stride"],
    anchor: str = _D["anchor"],
    mutual: bool = _D["mutual"],
    occupancy: bool = False,
    voxel_m: float = _D["voxel_m"],
    max_range_m: Optional[float] = None,
    near_m: float = _D["near_m"],
    far_m: float = _D["far_m"],
    bins: int = _D["bins"],
    spacing: str = _D["spacing"],
    traversal: str = _D["traversal"],
    occupancy_mode: str = _D["occupancy_mode"],
    downsample: bool = _D["downsample"],
    remove_outliers: bool = _D["remove_outliers"],
    outlier_k: Optional[int] = None,
    outlier_stddev: Optional[float] = None,
    dataset_depth_range: Optional[Tuple[float, float]] = None,
    dataset_min_depth_m: Optional[float] = None,
    dataset_max_depth_m: Optional[float] = None,
    scope_map: Optional[ScopeMap] = None,
) -> PairGroundTruth:
    """The ground truth of one pair of posed depth frames (C++ ``truth::ComputePairTruth``).

    The depth maps define the working resolution: every output is at their size (resize them
    first, e.g. with ``Scene.load(id, width, height)``). The two frames may have different
    sizes; each K must be the intrinsics of its own depth map.

    Args:
        depth0, depth1: depth maps [H, W], float32 or float64 (rounded to float32), planar z in
            metres along the camera's optical axis; 0, NaN, inf or outside
            [min_depth_m, max_depth_m] = no depth. Any strides. 2 <= H, W <= 8192.
        K0, K1: intrinsics [3, 3] (float or integer) of depth0 / depth1 at their size, pixels:
            [[fx, 0, cx], [0, fy, cy], [0, 0, 1]] with fx, fy > 0 and finite, the pixel centre
            convention of the module docstring (ScanNet's cx = 319.5 at width 640).
        world_from_cam0, world_from_cam1: camera-to-world poses [4, 4] (float or integer),
            OpenCV camera axes, metres: finite, last row [0, 0, 0, 1], rotation orthonormal to
            |R^T R - I| <= 1e-3 with det R > 0. Used as given (not re-orthonormalised).
        preset: label preset (PRESETS): "default", "occ2net", "occ2net-compat", "loftr",
            "superglue", "megadepth" (docs/GROUND_TRUTH.md §2); the options below override its
            fields.
        abs_tol_m: absolute depth tolerance (metres); None = the preset's.
        rel_tol: relative depth tolerance (fraction of z or of B's depth); None = the preset's.
        min_depth_m: minimum valid depth (metres), also the cheirality threshold; None = the
            dataset's range (``dataset_depth_range``), else the preset's
            (``PAIR_DEFAULTS["min_depth_m"]``).
        max_depth_m: maximum valid depth (metres); None = as min_depth_m
            (``PAIR_DEFAULTS["max_depth_m"]``).
        relative_to: "projected" | "observed": what rel_tol multiplies; None = the preset's.
        bounds: "pixel-area" | "strict": which projections lie inside B; None = the preset's.
        target_lookup: "nearest" | "truncate": B's pixel of a projection; None = the preset's.
        missing_target: "unknown" | "as-zero-depth": a projection onto B's missing depth;
            None = the preset's.
        stride: patch cell size in pixels at the working resolution (LoFTR's coarse level: 8).
        anchor: "center" | "corner": the anchor pixel of a cell (docs/GROUND_TRUTH.md §4).
        mutual: keep a visible-visible match only if it warps back into its cell.
        occupancy: also compute the 64-bin occupancy volumes of both cameras (the pair's two
            depth maps fused into one OctoMap-equivalent voxel map, docs/GROUND_TRUTH.md §5).
        voxel_m: voxel size of the fused map (metres).
        max_range_m: ray truncation of the fusion (metres; <= 0 unlimited); None = far_m,
            as a recipe's occupancy and ``occgt occupancy`` have it.
        near_m, far_m: first and last bin edge (planar depth, metres).
        bins: number of depth bins D, 1..64 (one uint64 word per ray).
        spacing: "linear" | "log" | "inverse": the bin edges.
        traversal: "exact" | "center": which voxels a bin's ray segment looks at.
        occupancy_mode: "octomap" (fused map) | "two_point" (the released Occ²Net target).
        downsample: one centroid per voxel before insertion (``occgt occupancy --downsample``,
            a recipe's ``occupancy.downsample``).
        remove_outliers: statistical outlier removal of the fused points (PCL's, after the
            downsampling; ``--remove-outliers``, ``occupancy.remove_outliers``).
        outlier_k, outlier_stddev: its neighbour count and threshold in standard deviations;
            None = ``PAIR_DEFAULTS["outlier_k"]`` / ``["outlier_stddev"]``; given only with
            remove_outliers=True (else ValueError).
        dataset_depth_range: (min, max) valid depth of the dataset the frames come from (a
            reader's ``Scene.min_depth_m``, ``Scene.max_depth_m``; pair_from_scene passes it):
            it replaces the preset's range unless the preset ignores datasets' ranges
            (occ2net-compat). None: no dataset.
        dataset_min_depth_m, dataset_max_depth_m: a range set for the whole dataset (a
            recipe's ``dataset.min_depth_m``/``max_depth_m``), applied whatever the preset;
            min_depth_m/max_depth_m still win over it. The order of all of these is
            docs/GROUND_TRUTH.md's (libgt/truth/pair_settings.h).
        scope_map: a map fused over a window of frames or the whole scene (``Scene.fuse``;
            its voxel_m, max_range_m and point filters must be the ones given here): the volumes are read
            from it instead of fusing the two depth maps. None = fuse the pair.

    Returns:
        A dict (PairGroundTruth) of NumPy arrays that own their memory, with the names, dtypes
        and values of the files of ``occgt pair`` (and ``occgt occupancy``):
        label01 uint8 [H0, W0], label10 uint8 [H1, W1] (codes: LABEL_NAMES),
        matches int32 [M, 2] (cell in image 0, cell in image 1; cells row-major, W/stride per
        row), match_type uint8 [M] (MATCH_TYPE_NAMES: 0 vv, 1 vo, 2 ov),
        match_xy float32 [M, 2] (the warped anchor in the other image, pixels),
        cells0 uint8 [H0/stride, W0/stride], cells1 uint8 [H1/stride, W1/stride] (the label of
        each cell's anchor), T_0to1 float64 [4, 4] (cam1_from_cam0 = inverse(world_from_cam1)
        @ world_from_cam0), metrics01, metrics10 (Metrics); with occupancy=True also occ0,
        known0 uint64 [H0/2, W0/2], occ1, known1 uint64 [H1/2, W1/2] (bit k: bin k occupied /
        known), bin_edges_m float64 [bins + 1] (metres) and fusion_stats (FusionStats of the
        map binned, the pair's own fusion or scope_map's; None for occupancy_mode
        "two_point": the points dropped as invalid or outside the key range are counted
        there); ``options``: the resolved options as a shard's sample records them
        (label_options, patch_options, occupancy_options).

    Raises:
        ValueError: an argument of the wrong type, dtype, shape or value, naming it; with
            occupancy=True, "voxel_m: ..." when the map's 16-bit key range (+-32766 voxels
            around the world origin) cannot hold a camera centre plus max_range_m (or, when
            max_range_m <= 0, its longest valid ray): the message names the smallest voxel
            size that works.
    """
    result: PairGroundTruth = _occgt.pair_ground_truth(
        depth0, depth1, K0, K1, world_from_cam0, world_from_cam1, preset,
        abs_tol_m=abs_tol_m, rel_tol=rel_tol, min_depth_m=min_depth_m, max_depth_m=max_depth_m,
        relative_to=relative_to, bounds=bounds, target_lookup=target_lookup,
        missing_target=missing_target, stride=stride, anchor=anchor, mutual=mutual,
        occupancy=occupancy, voxel_m=voxel_m, max_range_m=max_range_m, near_m=near_m,
        far_m=far_m, bins=bins, spacing=spacing, traversal=traversal,
        occupancy_mode=occupancy_mode, downsample=downsample, remove_outliers=remove_outliers,
        outlier_k=outlier_k, outlier_stddev=outlier_stddev,
        dataset_depth_range=dataset_depth_range,
        dataset_min_depth_m=dataset_min_depth_m, dataset_max_depth_m=dataset_max_depth_m,
        scope_map=scope_map)
    return result


def pair_options(preset: str = _D["preset"], **options: Any) -> Dict[str, Any]:
    """The options pair_ground_truth resolves from the same arguments (its ``options``
    entry), without computing anything: ``{"label_options": ..., "patch_options": ...,
    "occupancy_options": ... or None}`` with the names of a shard sample's json.

    Raises:
        ValueError: a bad value, naming the argument; TypeError: an unknown keyword.
    """
    result: Dict[str, Any] = _occgt.pair_options(preset, **options)
    return result


class ViewsGroundTruth(TypedDict):
    """What views_ground_truth returns (N views of H x W, Q tracks)."""

    visible_in: npt.NDArray[np.uint32]  # [N, H, W] bit j: the pixel is VISIBLE in view j
    occluded_in: npt.NDArray[np.uint32]  # [N, H, W] bit j: the pixel is OCCLUDED in view j
    valid: npt.NDArray[np.uint8]  # [N, H, W] 1: the view's own depth is valid
    seen_by: npt.NDArray[np.uint8]  # [N, H, W] other views in which the pixel is VISIBLE
    seen_by_histogram: npt.NDArray[np.int64]  # [N, N] [i, k]: valid pixels seen by k others
    query_view: int
    queries: npt.NDArray[np.int32]  # [Q, 2] (u, v) pixels of the query view
    track_xy: npt.NDArray[np.float32]  # [N, Q, 2] (x, y) in each view; NaN: not projected
    track_depth: npt.NDArray[np.float32]  # [N, Q] z in each view's camera (m); NaN: not projected
    track_state: npt.NDArray[np.uint8]  # [N, Q] TRACK_STATE_NAMES codes
    label_options: Dict[str, Any]  # the resolved label options (a shard's label_options)


def views_ground_truth(
    depths: Union[npt.ArrayLike, Sequence[npt.ArrayLike]],
    Ks: Union[npt.ArrayLike, Sequence[npt.ArrayLike]],
    world_from_cams: Union[npt.ArrayLike, Sequence[npt.ArrayLike]],
    *,
    preset: str = _D["preset"],
    queries: Optional[npt.ArrayLike] = None,
    num_tracks: int = VIEWS_DEFAULTS["num_tracks"],
    query_view: int = VIEWS_DEFAULTS["query_view"],
    seed: int = VIEWS_DEFAULTS["seed"],
    abs_tol_m: Optional[float] = None,
    rel_tol: Optional[float] = None,
    min_depth_m: Optional[float] = None,
    max_depth_m: Optional[float] = None,
    relative_to: Optional[str] = None,
    bounds: Optional[str] = None,
    target_lookup: Optional[str] = None,
    missing_target: Optional[str] = None,
    dataset_depth_range: Optional[Tuple[float, float]] = None,
    dataset_min_depth_m: Optional[float] = None,
    dataset_max_depth_m: Optional[float] = None,
) -> ViewsGroundTruth:
    """The dense ground truth of N posed depth views (C++ ``truth::ComputeViewsTruth``,
    docs/MULTIVIEW.md), from the pair labels: for j != i, bit j of ``visible_in[i]`` is
    pixel-for-pixel ``pair_ground_truth(depths[i], depths[j], ...)["label01"] == VISIBLE``
    (the same options); the same for ``occluded_in`` and OCCLUDED. The diagonal bit i of
    ``visible_in[i]`` is ``valid[i]`` (a view sees its own valid pixels), never OCCLUDED.

    Args:
        depths: N depth maps of one size [H, W] (a list, or one array [N, H, W]), float32 or
            float64, planar metres; 1 <= N <= 32.
        Ks: N intrinsics [3, 3] at the depth maps' size (a list or [N, 3, 3]).
        world_from_cams: N camera-to-world poses [4, 4] (a list or [N, 4, 4]), OpenCV axes,
            rigid as for pair_ground_truth.
        preset, abs_tol_m, rel_tol, min_depth_m, max_depth_m, relative_to, bounds,
            target_lookup, missing_target, dataset_depth_range, dataset_min_depth_m,
            dataset_max_depth_m: the label options, exactly as pair_ground_truth's.
        queries: integer [Q, 2] (u, v) pixels of the query view to track; None: sample
            num_tracks of its valid pixels (seeded, without replacement, returned in raster
            order; all of them when there are fewer).
        num_tracks: how many to sample (>= 0) when queries is None.
        query_view: the view whose pixels are the queries, 0..N-1.
        seed: of the sampling (the same seed gives the same queries on every machine).

    Returns:
        A dict (ViewsGroundTruth) of arrays that own their memory. ``track_xy[j]`` is the
        pair warp of the queries into view j (bit for bit), ``track_state[j]`` the state
        (TRACK_STATE_NAMES) of the pair label query_view -> j, ``track_depth[j]`` the point's
        depth in view j's camera. VGGT's ``tracks`` is track_xy and its ``track_vis_mask`` is
        ``track_state == TRACK_VISIBLE``.

    Raises:
        ValueError: a bad argument, naming it (more than 32 views, mismatched counts or
            shapes, a pose that is not rigid, a query outside the image, a bad option).
    """
    result: ViewsGroundTruth = _occgt.views_ground_truth(
        depths, Ks, world_from_cams, preset=preset, queries=queries, num_tracks=num_tracks,
        query_view=query_view, seed=seed, abs_tol_m=abs_tol_m, rel_tol=rel_tol,
        min_depth_m=min_depth_m, max_depth_m=max_depth_m, relative_to=relative_to,
        bounds=bounds, target_lookup=target_lookup, missing_target=missing_target,
        dataset_depth_range=dataset_depth_range, dataset_min_depth_m=dataset_min_depth_m,
        dataset_max_depth_m=dataset_max_depth_m)
    return result


class SeenBy(TypedDict):
    """What views_seen_by returns (N views of H x W)."""

    seen_by: npt.NDArray[np.uint8]  # [N, H, W] other views in which the pixel is VISIBLE
    seen_by_histogram: npt.NDArray[np.int64]  # [N, N] [i, k]: valid pixels seen by k others


def views_seen_by(visible_in: npt.ArrayLike, valid: npt.ArrayLike) -> SeenBy:
    """``seen_by`` and ``seen_by_histogram`` of stored bitmasks (C++ ``truth::CountSeenBy``):
    for the ``visible_in`` and ``valid`` of ``views_ground_truth`` (or of an N-view shard),
    the same arrays ``views_ground_truth`` returned with them.

    Args:
        visible_in: uint32 [N, H, W], 1 <= N <= 32 (bit j: VISIBLE in view j).
        valid: uint8 [N, H, W], 0 or 1.

    Raises:
        ValueError: another dtype or shape, a bit set for a view >= N, a valid value other
            than 0 and 1.
    """
    result: SeenBy = _occgt.views_seen_by(visible_in, valid)
    return result


def dense_volume(occ: npt.ArrayLike, known: npt.ArrayLike,
                 bins: int = _D["bins"]) -> npt.NDArray[np.uint8]:
    """The dense occupancy volume of one camera (C++ ``occupancy::DenseVolume``).

    Args:
        occ: uint64 [H/2, W/2] words of pair_ground_truth's occ0/occ1 (bit k: bin k occupied).
        known: uint64 [H/2, W/2], known0/known1 (bit k: bin k occupied or free).
        bins: number of depth bins D used for them, 1..64.

    Returns:
        uint8 [bins, H/2, W/2]: 0 free, 1 occupied, 255 unknown (bin k covers planar depth
        [bin_edges_m[k], bin_edges_m[k + 1])), like ``occgt occupancy --dense``.
    """
    return _occgt.dense_volume(occ, known, bins)


def depth_at_image_size(
    depth: npt.ArrayLike, K: npt.ArrayLike, scale: Tuple[float, float], width: int, height: int
) -> Tuple[npt.NDArray[np.float32], npt.NDArray[np.float64]]:
    """A depth map and its intrinsics at the size of a resized image (LoFTR's ``scale0``).

    Args:
        depth: depth map [H, W] float32/float64, planar metres (0 = none); it may be padded at
            the bottom and right (MegaDepth's 2000 x 2000 maps).
        K: intrinsics [3, 3] of the depth map's pixels.
        scale: (sx, sy) depth-map pixels per image pixel (LoFTR's ``scale0``: original size /
            resized size), finite and > 0.
        width, height: the resized image's size in pixels (without its padding).

    Returns:
        (depth float32 [height, width], K float64 [3, 3]): the top-left round(width * sx) x
        round(height * sy) pixels of depth resampled nearest to width x height, and K for it,
        with the pixel-centre rules of docs/GROUND_TRUTH.md §1 (fx' = fx / sx,
        cx' = (cx + 0.5) / sx - 0.5).

    Raises:
        ValueError: a bad argument, or an image that covers more than the depth map.
    """
    return _occgt.depth_at_image_size(depth, K, scale, width, height)


def load_mesh(path: Union[str, "os.PathLike[str]"]) -> Mesh:
    """A triangle mesh read from a PLY file, with its ray-casting BVH (Embree) built once.

    The Mesh is immutable: reuse it for every render_depth call, from any number of threads.

    Args:
        path: a PLY file (ASCII or binary; vertex x, y, z float or double; faces
            ``list uchar|int int|uint``; other properties ignored), metres.

    Raises:
        ValueError: an unreadable, malformed, truncated or oversized file (the message names it).
        TypeError: path is not a str or os.PathLike.
    """
    try:
        file = os.fspath(path)
    except TypeError:
        raise TypeError(f"path: expected a path (str or os.PathLike), got "
                        f"{type(path).__name__}") from None
    return _occgt.load_mesh(file)


def render_depth(
    mesh: Mesh,
    K: npt.ArrayLike,
    world_from_cam: npt.ArrayLike,
    width: int,
    height: int,
    *,
    model: str = RENDER_DEFAULTS["model"],
    dist: Optional[npt.ArrayLike] = None,
    near_m: float = RENDER_DEFAULTS["near_m"],
    far_m: float = RENDER_DEFAULTS["far_m"],
) -> npt.NDArray[np.float32]:
    """Planar depth of a mesh seen by a camera (docs/GROUND_TRUTH.md "Depth sources").

    The ray of pixel (u, v) passes through the pixel's centre, the continuous point (u, v)
    (through its exact undistorted direction for a distorted camera); the first surface hit
    gives the pixel's camera z in metres.

    Args:
        mesh: from load_mesh.
        K: intrinsics [3, 3] of the (distorted) image, OpenCV's pixel convention.
        world_from_cam: rigid pose [4, 4], camera to the mesh's frame, OpenCV axes, metres.
        width, height: image size in pixels.
        model: "pinhole", "opencv" (dist = k1, k2, p1, p2[, k3]) or "opencv_fisheye"
            (dist = k1, k2, k3, k4).
        dist: the distortion coefficients; None for "pinhole".
        near_m, far_m: a first surface outside [near_m, far_m] gives 0.

    Returns:
        float32 [height, width] planar depth in metres; 0 where the ray hits nothing, its first
        surface is outside [near_m, far_m], or the pixel has no ray (outside a lens model's
        monotonic range).

    Raises:
        ValueError: a bad argument (the message names it).
    """
    return _occgt.render_depth(mesh, K, world_from_cam, width, height, model=model, dist=dist,
                               near_m=near_m, far_m=far_m)


def open_dataset(root: Union[str, "os.PathLike[str]"], format: str, *,
                 device: str = DATASET_DEFAULTS["device"],
                 tum_max_dt_s: Optional[float] = None) -> Dataset:
    """A dataset read by occgt's own readers (docs/DATASETS.md).

    Args:
        root: the dataset folder (or a scene folder / generic manifest folder).
        format: one of FORMATS: "scannet", "tartanair", "sevenscenes", "tum", "megadepth",
            "generic", "scannetpp".
        device: "scannetpp" only: "dslr" or "iphone" (the camera whose frames are read).
        tum_max_dt_s: "tum": the association tolerance in seconds (a recipe's
            ``dataset.tum_max_dt_s``; None: ``DATASET_DEFAULTS["tum_max_dt_s"]``).

    Returns:
        A Dataset: ``.scenes()`` lists the scene names, ``.scene(name)`` reads one scene
        (``.frames``: id, number, usable, reason, detail, K at the depth resolution,
        world_from_cam; ``.load(frame_id, width=640, height=480)`` -> (depth float32 [H, W] metres,
        K float64 [3, 3] at W x H, world_from_cam float64 [4, 4])).
    """
    try:
        path = os.fspath(root)
    except TypeError:
        raise TypeError(f"root: expected a path (str or os.PathLike), got "
                        f"{type(root).__name__}") from None
    return Dataset(path, format, device=device, tum_max_dt_s=tum_max_dt_s)


def pair_from_scene(scene: Scene, id0: str, id1: str, *, width: int = _D["width"],
                    height: int = _D["height"], preset: str = _D["preset"], scope: str = "pair",
                    depth_source: str = DATASET_DEFAULTS["depth_source"],
                    fused_depth: Optional[Dict[str, float]] = None,
                    **options: Any) -> PairGroundTruth:
    """pair_ground_truth of frames id0, id1 of a scene at width x height, with the scene's
    depth range unless ``min_depth_m``/``max_depth_m`` are given (occ2net-compat: every finite
    depth > 0, as its release compares them): the arrays and metrics that
    ``occgt pair --root R --format F --scene S --frames id0,id1 --resolution WxH`` writes (and,
    with ``occupancy=True``, ``occgt occupancy ... --scope SCOPE``).

    ``scope``: the frames fused for the occupancy volumes: "pair", "window:N" or "scene:S"
    (``Scene.fuse``; a scene map is fused again at each call: to share one map between the
    pairs of a scene, call ``Scene.fuse`` once and pass ``scope_map``, whose scope is then
    the pair's: a ``scope`` other than "pair" that is not the map's is a ValueError, not
    ignored). ``options`` are the
    keyword arguments of pair_ground_truth. ``depth_source``: "sensor" (the depth files),
    "mesh" or "fused" (``Scene.mesh_path`` rendered, or fused with the files;
    docs/GROUND_TRUTH.md "Depth sources"), as ``occgt pair --depth-source``; with another
    scope than "pair" only "sensor" (the scope's frames are fused from their depth files);
    ``fused_depth``: the tolerances of "fused" (``Scene.load``; a recipe's
    ``dataset.fused_depth``).
    """
    if not isinstance(scene, Scene):
        raise TypeError(f"scene: expected an occgt.Scene (Dataset.scene), got "
                        f"{type(scene).__name__}")
    if not isinstance(scope, str):
        raise TypeError(f"scope: expected a str, got {type(scope).__name__}")
    if scope != "pair" and not options.get("occupancy"):
        raise ValueError(f"scope: {scope!r} is the frames fused for occupancy, which is off; "
                         f"pass occupancy=True")
    if depth_source != "sensor" and scope != "pair" and options.get("occupancy"):
        raise ValueError("depth_source: a scope other than 'pair' fuses sensor depth; use "
                         f"scope='pair' with depth_source {depth_source!r}")
    depth0, K0, world_from_cam0 = scene.load(id0, width, height, depth_source=depth_source,
                                             fused_depth=fused_depth)
    depth1, K1, world_from_cam1 = scene.load(id1, width, height, depth_source=depth_source,
                                             fused_depth=fused_depth)
    options.setdefault("dataset_depth_range", (scene.min_depth_m, scene.max_depth_m))
    scope_map = options.get("scope_map")
    if isinstance(scope_map, ScopeMap) and scope_map.scene != scene.name:
        raise ValueError(f"scope_map: fused from scene {scope_map.scene}; expected scene "
                         f"{scene.name} (the pair's)")
    # The map decides what was fused: another scope asked for beside it is not dropped.
    if isinstance(scope_map, ScopeMap) and scope != "pair" and scope_name(scope) != scope_map.scope:
        raise ValueError(f"scope: {scope!r}, but scope_map was fused over {scope_map.scope!r}; "
                         f"pass the map's scope or none")
    if scope != "pair" and options.get("occupancy") and "scope_map" not in options:
        options["scope_map"] = fuse_scope(scene, id0, id1, width, height, scope, preset, options)
    return pair_ground_truth(depth0, depth1, K0, K1, world_from_cam0, world_from_cam1, preset,
                             **options)


def scope_name(scope: Any) -> str:
    """The name ``ScopeMap.scope`` gives a fusion scope ("pair", "window:N", "scene:S" with
    1 <= N, S < 10^9; leading zeros dropped), or TypeError / ValueError naming ``scope``
    (occupancy::ParseFusionScope, as ``Scene.fuse`` reads it; PairIndexDataset checks its
    scope with it before any scene is read)."""
    if not isinstance(scope, str):
        raise TypeError(f"scope: expected a str, got {type(scope).__name__}")
    name: str = _occgt.scope_name(scope)
    return name


#: The keyword arguments of pair_ground_truth that Scene.fuse takes too (the map must be
#: fused with the options the pair uses).
FUSE_OPTIONS = ("voxel_m", "max_range_m", "far_m", "min_depth_m", "max_depth_m",
                "dataset_min_depth_m", "dataset_max_depth_m", "downsample", "remove_outliers",
                "outlier_k", "outlier_stddev")


def fuse_scope(scene: Scene, id0: str, id1: str, width: int, height: int, scope: str,
               preset: str, options: Dict[str, Any]) -> ScopeMap:
    """``Scene.fuse`` with the options of pair_ground_truth's keyword arguments ``options``
    (those of FUSE_OPTIONS; the rest are not the fusion's)."""
    return scene.fuse(id0, id1, width, height, scope=scope, preset=preset,
                      **{k: options.get(k) for k in FUSE_OPTIONS})

