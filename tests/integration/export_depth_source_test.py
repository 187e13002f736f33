"""The exports write the depth the build used (docs/EXPORTS.md "Which depth the exports
write"): the real 7-Scenes sample built with `dataset.depth_source: mesh` and the shared TSDF
mesh (../shared/data, required). Every DUSt3R depth PNG equals the depth `occgt render`
writes for that frame (round(1000 d) mm of the mesh at 640x480), not the sensor's (which
differs from it on many pixels); the LoFTR tree's and glue-factory's depth the same rendered
depth in their units. A sensor build of the same recipe still writes the sensor's depth."""
import json
import os
import re
import sys

import cv2
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common  # noqa: E402

ROOT = common.shared("sevenscenes")
MESH = common.shared("meshes/sevenscenes-rgbd-frames-tsdf.ply")
SCENE = "rgbd-frames"


def recipe_text(depth_source):
    with open(os.path.join(common.SOURCE, "recipes", "sevenscenes-sample.yaml")) as f:
        text = f.read()
    text = text.replace("${OCCGT_SHARED_DATA:-../../shared/data}/sevenscenes", ROOT)
    text = text.replace("quota_per_scene: 12", "quota_per_scene: 4")
    text = re.sub(r"occupancy:\n  enabled: true\n(  .*\n)*", "occupancy:\n  enabled: false\n", text)
    text = text.replace("occupancy: true}", "occupancy: false}")
    if depth_source:
        text = text.replace("  frame_stride: 2\n", f"  frame_stride: 2\n  depth_source: {depth_source}\n"
                            f"  mesh_path: {MESH}\n")
    assert "dust3r_export: true" in text and "tree: true" in text and "gluefactory_export: true" in text
    return text


def build(name, depth_source):
    out = common.scratch("export_depth_" + name)
    recipe = os.path.join(out, "recipe.yaml")
    with open(recipe, "w") as f:
        f.write(recipe_text(depth_source))
    common.occgt("build", recipe, "--out", os.path.join(out, "build"))
    return os.path.join(out, "build")


def read_png(path):
    raw = cv2.imread(path, cv2.IMREAD_UNCHANGED)
    assert raw is not None and raw.dtype == np.uint16 and raw.shape == (480, 640), path
    return raw


def sensor_mm(number):
    raw = read_png(os.path.join(ROOT, SCENE, f"frame-{number:06d}.depth.png")).copy()
    raw[raw == 65535] = 0
    return raw


def dust3r_views(build_dir):
    with open(os.path.join(build_dir, "dust3r", "export.json")) as f:
        folders = json.load(f)["scenes"]
    (folder, scene), = folders.items()
    assert scene == SCENE, folders
    names = sorted(int(p[:-4]) for p in os.listdir(os.path.join(build_dir, "dust3r", folder, "depth")))
    assert len(names) >= 2, names
    return folder, names


def main():
    mesh_build = build("mesh", "mesh")
    folder, numbers = dust3r_views(mesh_build)
    rendered = common.scratch("export_depth_render")
    common.occgt("render", "--root", ROOT, "--format", "sevenscenes", "--scene", SCENE,
                 "--mesh", MESH, "--frames", ",".join(f"{n:06d}" for n in numbers),
                 "--resolution", "640x480", "--out", rendered)
    with open(os.path.join(mesh_build, "loftr", "tree.json")) as f:
        tree = json.load(f)
    assert tree["frames"] >= len(numbers) and tree["linked"] == 0, tree  # nothing linked
    differ_total = 0
    for n in numbers:
        want = np.load(os.path.join(rendered, f"{n:06d}_depth.npy")).astype(np.float64)
        want_mm = read_png(os.path.join(rendered, f"{n:06d}_depth.png"))
        assert np.array_equal(want_mm, np.floor(want * 1000 + 0.5).astype(np.uint16)), n
        got = read_png(os.path.join(mesh_build, "dust3r", folder, "depth", f"{n}.png"))
        assert np.array_equal(got, want_mm), (n, int((got != want_mm).sum()))
        # The LoFTR tree (mm at 640x480) holds the same; glue-factory round(256 d).
        loftr = read_png(os.path.join(mesh_build, "loftr", "data", "scene0000_00", "depth", f"{n}.png"))
        assert np.array_equal(loftr, want_mm), (n, int((loftr != want_mm).sum()))
        gf = read_png(os.path.join(mesh_build, "gluefactory", "data", folder, "depths", f"{n}.png"))
        # C's round(): halves away from zero (d * 256 of a float32 often is an exact half).
        assert np.array_equal(gf, np.floor(want * 256 + 0.5).astype(np.uint16)), n
        # Not the sensor's: the two differ by more than a centimetre on many pixels.
        sensor = sensor_mm(n)
        differ = np.abs(got.astype(np.int64) - sensor.astype(np.int64)) > 10
        assert differ.mean() > 0.01, (n, float(differ.mean()))
        differ_total += int(differ.sum())
    # The same recipe with the sensor's depth: the export holds the sensor's millimetres.
    sensor_build = build("sensor", None)
    folder_s, numbers_s = dust3r_views(sensor_build)
    for n in numbers_s:
        got = read_png(os.path.join(sensor_build, "dust3r", folder_s, "depth", f"{n}.png"))
        assert np.array_equal(got, sensor_mm(n)), n
    print(f"export depth: {len(numbers)} DUSt3R views equal occgt render's depth "
          f"({differ_total} pixels off the sensor's by > 1 cm); sensor build: {len(numbers_s)} "
          "views equal the sensor's")


if __name__ == "__main__":
    main()
