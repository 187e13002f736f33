#!/usr/bin/env python3
"""MD5 of every .npy member of every shard of a built split, one line each, sorted:
"<member path> <md5>" (a .npy.gz member: its gunzipped bytes, named without ".gz", so the
lines do not depend on sample.compression). The ground truth of the shipped recipes must stay byte-identical
across refactors (issue 19): tests/integration/golden_test.py compares these lines with
the files recorded next to this script. Record anew, deliberately, only when a change of
the ground truth is intended:  tests/golden/npy_digests.py OUT_DIR > tests/golden/NAME.txt
"""
import gzip
import hashlib
import json
import os
import sys
import tarfile


def digests(split_dir):
    with open(os.path.join(split_dir, "index.json")) as f:
        index = json.load(f)
    lines = []
    for shard in index["shardlist"]:
        with tarfile.open(os.path.join(split_dir, shard["url"])) as tar:
            for member in tar:
                name = member.name
                if not member.isfile() or not name.endswith((".npy", ".npy.gz")):
                    continue
                data = tar.extractfile(member).read()
                if name.endswith(".gz"):  # sample.compression: deflate (the default)
                    name, data = name[:-3], gzip.decompress(data)
                lines.append(f"{name} {hashlib.md5(data).hexdigest()}")
    return sorted(lines)


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: npy_digests.py SPLIT_DIR")
    print("\n".join(digests(sys.argv[1])))
