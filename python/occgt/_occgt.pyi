"""Type stubs of the extension module occgt._occgt (python/src/*.cc). Use the package
``occgt``: its functions document every argument (python/occgt/__init__.py)."""
import os
from typing import Any, Dict, List, Optional, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str
LABEL_NAMES: Tuple[str, ...]  # index = uint8 label code
MATCH_TYPE_NAMES: Tuple[str, ...]  # index = uint8 match type code ("vv", "vo", "ov")
PRESETS: Tuple[str, ...]  # label presets
FORMATS: Tuple[str, ...]  # dataset formats of open_dataset

PAIR_DEFAULTS: Dict[str, Any]  # default of each pair_ground_truth argument, from the C++
VIEWS_DEFAULTS: Dict[str, Any]  # views_ground_truth: num_tracks, query_view, seed
RENDER_DEFAULTS: Dict[str, Any]  # render_depth: model, near_m, far_m
SUPERVISION_DEFAULTS: Dict[str, Any]  # loftr_coarse_supervision: coarse_stride, compat
DATASET_DEFAULTS: Dict[str, Any]  # Dataset: device; Scene.load: depth_source; fused_depth

def pair_ground_truth(
    depth0: npt.ArrayLike,
    depth1: npt.ArrayLike,
    K0: npt.ArrayLike,
    K1: npt.ArrayLike,
    world_from_cam0: npt.ArrayLike,
    world_from_cam1: npt.ArrayLike,
    preset: str = ...,
    **options: Any,
) -> Any: ...  # occgt.PairGroundTruth
def pair_options(preset: str = ..., **options: Any) -> Dict[str, Any]: ...
def scope_name(scope: str) -> str: ...
def encode_sample_color(rgb: npt.ArrayLike, format: str) -> bytes: ...
TRACK_STATE_NAMES: Tuple[str, ...]  # index = uint8 code of views_ground_truth's track_state
def views_ground_truth(
    depths: Any,
    Ks: Any,
    world_from_cams: Any,
    *,
    preset: str = ...,
    queries: Optional[npt.ArrayLike] = ...,
    num_tracks: int = ...,
    query_view: int = ...,
    seed: int = ...,
    **options: Any,
) -> Any: ...  # occgt.ViewsGroundTruth
def gunzip_npy(gz: Any, what: str) -> bytearray: ...  # a bytes-like gzip'd .npy member in
# (descr, fortran_order, shape, data_offset) of the .npy member buf[offset:offset + size]
def npy_header(buf: Any, offset: int, size: int, what: str) -> Tuple[str, bool, Tuple[int, ...], int]: ...
# [(key, start, length, {field: (offset from start, size)})] of a tar shard, in file order
def shard_samples(path: str) -> List[Tuple[str, int, int, Dict[str, Tuple[int, int]]]]: ...
def shard_index(split_dir: str) -> Tuple[str, str, List[Tuple[str, int, int]]]: ...
def views_seen_by(visible_in: npt.ArrayLike, valid: npt.ArrayLike) -> Any: ...  # occgt.SeenBy
def check_resolution(width: int, height: int) -> None: ...
def views_options(preset: str = ..., num_tracks: int = ..., query_view: int = ..., seed: int = ...,
                  **label_options: Any) -> Dict[str, Any]: ...
def check_pair_sample(meta: str, arrays: Dict[str, npt.NDArray[Any]], where: str) -> None: ...
def check_views_sample(meta: str, arrays: Dict[str, npt.NDArray[Any]],
                       where: str) -> npt.NDArray[np.uint8]: ...
def dense_volume(occ: npt.ArrayLike, known: npt.ArrayLike, bins: int = ...) -> npt.NDArray[np.uint8]: ...

WARP_STATUS_NAMES: Tuple[str, ...]  # index = uint8 code of status0/status1
def loftr_coarse_supervision(
    depth0: npt.ArrayLike,
    depth1: npt.ArrayLike,
    K0: npt.ArrayLike,
    K1: npt.ArrayLike,
    T_0to1: npt.ArrayLike,
    T_1to0: Optional[npt.ArrayLike] = None,
    *,
    coarse_stride: int = ...,
    scale0: Tuple[float, float] = (1.0, 1.0),
    scale1: Tuple[float, float] = (1.0, 1.0),
    image_size0: Optional[Tuple[int, int]] = None,
    image_size1: Optional[Tuple[int, int]] = None,
    compat: bool = ...,
    mask0: Optional[npt.ArrayLike] = None,
    mask1: Optional[npt.ArrayLike] = None,
) -> Any:
    """LoFTR's coarse supervision of one pair (libgt/truth/loftr_supervision.h): a dict with
    cells_shape0/1 (h_c, w_c), grid0/1 float32 [L, 2] (corner grid points, depth-map
    pixels), warped0/1 float32 [L, 2] (into the other image; NaN without depth, behind or
    padded), target0/1 int32 [L] (target cell, -1 none; compat 0), status0/1 uint8 [L]
    (WARP_STATUS_NAMES) and matches int32 [M, 2] (i, j). image_size: (height, width) of the
    image the grid covers (default the depth map's); scale: (sx, sy) depth-map pixels per
    image pixel; mask: bool/int [h_c, w_c] over the coarse cells, 0 on the padding of a
    padded image (LoFTR's MegaDepth mask0/mask1). Batched torch form:
    occgt.torch.loftr_supervision."""
    ...

def depth_at_image_size(
    depth: npt.ArrayLike, K: npt.ArrayLike, scale: Tuple[float, float], width: int, height: int
) -> Tuple[npt.NDArray[np.float32], npt.NDArray[np.float64]]:
    """(depth, K) at the size of LoFTR's resized image; see occgt.depth_at_image_size."""
    ...

def target_cells(
    xy: npt.ArrayLike, cells_w: int, cells_h: int, stride: int, anchor: str
) -> npt.NDArray[np.int32]:
    """The target cell of each point of xy [M, 2] in a cells_w x cells_h grid (the patch
    matches' rule), -1 outside the grid or not finite."""
    ...

class Frame:
    """One frame of a scene as its reader lists it (metadata only)."""

    @property
    def id(self) -> str: ...
    @property
    def number(self) -> int: ...
    @property
    def usable(self) -> bool: ...
    @property
    def reason(self) -> str: ...  # why unusable: a stable category ('' when usable)
    @property
    def detail(self) -> str: ...  # where it was found: '<file>:<line>: non-finite value' ('' if none)
    @property
    def width(self) -> int: ...  # of the depth map, pixels
    @property
    def height(self) -> int: ...
    @property
    def K(self) -> npt.NDArray[np.float64]: ...  # [3, 3] at width x height, pixels
    @property
    def world_from_cam(self) -> npt.NDArray[np.float64]: ...  # [4, 4], OpenCV axes, metres
    @property
    def depth_path(self) -> str: ...
    @property
    def color_path(self) -> str: ...

class ScopeMap:
    """An occupancy map fused over a scope of a scene (Scene.fuse)."""

    @property
    def scene(self) -> str: ...
    @property
    def scope(self) -> str: ...  # "pair", "window:N" or "scene:S"
    @property
    def fused_ids(self) -> List[str]: ...
    @property
    def skipped(self) -> List[Tuple[str, str]]: ...  # (frame id, reason)
    @property
    def fusion_stats(self) -> Dict[str, int]: ...  # occgt.FusionStats of the fused frames
    @property
    def voxel_m(self) -> float: ...
    @property
    def max_range_m(self) -> float: ...

class Scene:
    """One scene of a dataset: its frames and how to load them at a working resolution."""

    @property
    def name(self) -> str: ...
    @property
    def format(self) -> str: ...
    @property
    def path(self) -> str: ...
    @property
    def min_depth_m(self) -> float: ...  # the dataset's valid depth range, metres
    @property
    def max_depth_m(self) -> float: ...
    @property
    def frames(self) -> List[Frame]: ...
    @property
    def mesh_path(self) -> str: ...  # the mesh depth_source "mesh"/"fused" renders ('' = none)
    @mesh_path.setter
    def mesh_path(self, path: Union[str, "os.PathLike[str]"]) -> None: ...
    def load(
        self, frame_id: str, width: int = ..., height: int = ..., *, depth_source: str = ...,
        fused_depth: Optional[Dict[str, float]] = ...
    ) -> Tuple[npt.NDArray[np.float32], npt.NDArray[np.float64], npt.NDArray[np.float64]]:
        """(depth float32 [height, width] planar metres, 0 = invalid; K float64 [3, 3] at
        width x height; world_from_cam float64 [4, 4]) of a usable frame: depth resized with
        nearest neighbour, K rescaled with the pixel-area rule. ValueError for an unknown or
        unusable frame_id or an unreadable depth file."""
        ...
    def fuse(
        self, id0: str, id1: str, width: int = ..., height: int = ..., *, scope: str = "pair",
        voxel_m: Optional[float] = None, max_range_m: Optional[float] = None,
        far_m: Optional[float] = None, min_depth_m: Optional[float] = None,
        max_depth_m: Optional[float] = None, preset: str = ...,
        dataset_min_depth_m: Optional[float] = None, dataset_max_depth_m: Optional[float] = None,
        downsample: Optional[bool] = None, remove_outliers: Optional[bool] = None,
        outlier_k: Optional[int] = None, outlier_stddev: Optional[float] = None
    ) -> ScopeMap:
        """The occupancy map of the pair fused over scope ("pair", "window:N", "scene:S"), for
        pair_ground_truth(..., occupancy=True, scope_map=...)."""
        ...
    def load_color(
        self, frame_id: str, width: int = ..., height: int = ...
    ) -> npt.NDArray[np.uint8]:
        """Colour of a frame at width x height: uint8 [height, width, 3], R G B, resized
        bilinearly from the colour camera (the pixels of a shard's image0/image1). ValueError
        when the frame has no colour image or it cannot be read."""
        ...

class Dataset:
    """A dataset root read by one of occgt's readers."""

    def __init__(self, root: str, format: str, *, device: str = ...,
                 tum_max_dt_s: Optional[float] = ...) -> None: ...
    @property
    def root(self) -> str: ...
    @property
    def format(self) -> str: ...
    def scenes(self) -> List[str]: ...
    def scene(self, name: str) -> Scene: ...

class Mesh:
    """A triangle mesh and its ray-casting BVH (load_mesh)."""
    @property
    def path(self) -> str: ...
    @property
    def num_vertices(self) -> int: ...
    @property
    def num_triangles(self) -> int: ...

def load_mesh(path: str) -> Mesh: ...
def render_depth(
    mesh: Mesh,
    K: npt.ArrayLike,
    world_from_cam: npt.ArrayLike,
    width: int,
    height: int,
    *,
    model: str = ...,
    dist: Optional[npt.ArrayLike] = ...,
    near_m: float = ...,
    far_m: float = ...,
) -> npt.NDArray[np.float32]: ...
