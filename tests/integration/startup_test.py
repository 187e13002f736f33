"""The occgt binary's start-up stays cheap (docs/PERFORMANCE.md, "Threads and tasks"): it
must not load OpenCV's imgcodecs (GDAL and ~140 libraries behind it; occgt decodes images
with libpng and libjpeg-turbo, libgt/io/codec.h) nor libpcl_filters and its PCL
dependencies (the filters are compiled from PCL's headers in libgt/occupancy/fusion.cc).
Checked on the libraries the dynamic loader resolves (`ldd`), not on a timing. The
libraries occgt does need are present, so that the check cannot pass on a broken ldd."""
import os
import subprocess
import sys

sys.path.insert(0, os.path.dirname(__file__))
import common  # noqa: E402

FORBIDDEN = ["libopencv_imgcodecs", "libgdal", "libpcl_filters", "libpcl_sample_consensus",
             "libpcl_search", "libpcl_kdtree", "libpcl_octree"]
REQUIRED = ["libopencv_core", "libpng16", "libjpeg", "libpcl_common", "liboctomap", "libtbb",
            "libOpenEXR", "libcrypto"]


def main():
    binary = os.environ["OCCGT_BINARY"]
    ldd = subprocess.run(["ldd", binary], capture_output=True, text=True, check=True).stdout
    names = [line.split()[0] for line in ldd.splitlines() if line.strip()]
    for bad in FORBIDDEN:
        hits = [n for n in names if n.startswith(bad)]
        assert not hits, f"occgt loads {hits} (start-up cost; see the docstring)"
    for good in REQUIRED:
        assert any(n.startswith(good) for n in names), f"ldd does not list {good}: {names}"
    missing = [line for line in ldd.splitlines() if "not found" in line]
    assert not missing, missing
    common.occgt("--help")
    print(f"startup: {len(names)} shared libraries, none of {len(FORBIDDEN)} forbidden ones")


if __name__ == "__main__":
    main()
