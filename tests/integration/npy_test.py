"""occgt's .npy writer read by NumPy: the depth files of `occgt synth` load with the right
dtype and shape, their data starts at a multiple of 64 bytes (np.load with mmap_mode
reports the offset), the header is version 1.0 and ends in '\\n', and the values agree with
a second read through np.memmap at that offset. (NumPy-written .npy/.npz read by occgt, and
occgt's .npz read by NumPy, are covered by the gtest io/npy: Npy.ExchangeWithNumPy.)"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
import common  # noqa: E402


def main():
    out = common.scratch("npy_synth")
    common.occgt("synth", "--out", out, "--scenes", 1, "--frames", 3, "--resolution", "96x64")
    depth_dir = os.path.join(out, "synth_000", "depth")
    names = sorted(os.listdir(depth_dir))
    assert names == ["000000.npy", "000001.npy", "000002.npy"], names
    for name in names:
        path = os.path.join(depth_dir, name)
        with open(path, "rb") as f:
            raw = f.read()
        assert raw[:8] == b"\x93NUMPY\x01\x00", raw[:8]
        header_len = int.from_bytes(raw[8:10], "little")
        offset = 10 + header_len
        assert offset % 64 == 0, offset
        assert raw[offset - 1:offset] == b"\n"
        header = raw[10:offset].decode("latin1")
        assert header.startswith("{'descr': '<f4', 'fortran_order': False, 'shape': (64, 96), }")
        a = np.load(path)
        assert a.dtype == np.dtype("<f4") and a.shape == (64, 96), (a.dtype, a.shape)
        m = np.load(path, mmap_mode="r")
        assert m.offset == offset
        direct = np.memmap(path, dtype="<f4", mode="r", offset=offset, shape=(64, 96))
        assert np.array_equal(a, direct)
        assert len(raw) == offset + 64 * 96 * 4
        assert (a >= 0).all() and (a > 0).mean() > 0.8
    print("ok")


if __name__ == "__main__":
    main()
