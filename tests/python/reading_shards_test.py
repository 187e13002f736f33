"""Every code block of docs/READING_SHARDS.md runs as written.

`occgt build recipes/demo.yaml --out out/demo` in a scratch folder, then, from that folder,
every ```python block of the page in order in one namespace (stdout captured and checked),
every ```json block parsed and compared with the split's own file, and the ```text layout of
"The folder" checked against the files of the split. A block in any other language (or
none) fails the test, so a new example cannot be added without running."""
from __future__ import annotations

import contextlib
import io
import json
import os
import re
import sys
import unittest
from typing import Any, Dict, List, Tuple

sys.path.insert(0, os.path.dirname(__file__))
import common  # noqa: E402

PAGE = os.path.join(common.SOURCE, "docs", "READING_SHARDS.md")


def blocks(path: str) -> List[Tuple[str, str]]:
    """(language, text) of every fenced block, in order."""
    with open(path) as f:
        text = f.read()
    return re.findall(r"^```(\w*)\n(.*?)^```", text, flags=re.S | re.M)


class ReadingShards(unittest.TestCase):
    def test_every_block_runs_as_written(self) -> None:
        work = common.scratch("reading_shards")
        common.occgt("build", "--json", os.path.join(common.SOURCE, "recipes", "demo.yaml"), "--out",
                     os.path.join(work, "out", "demo"))
        found = blocks(PAGE)
        languages = [lang for lang, _ in found]
        self.assertGreaterEqual(languages.count("python"), 6, languages)
        namespace: Dict[str, Any] = {"__name__": "__reading_shards__"}
        out = io.StringIO()
        cwd = os.getcwd()
        os.chdir(work)
        try:
            for k, (lang, text) in enumerate(found):
                where = f"docs/READING_SHARDS.md block {k} ({lang or 'no language'})"
                with self.subTest(block=k):
                    if lang == "python":
                        with contextlib.redirect_stdout(out):
                            exec(compile(text, where, "exec"), namespace)
                    elif lang == "json":
                        self.check_json(json.loads(text), where)
                    elif lang == "text":
                        if text.startswith("DIR/"):
                            self.check_folder(text, where)
                    else:
                        self.fail(f"{where}: expected a python, json or text block")
        finally:
            os.chdir(cwd)
        printed = out.getvalue()
        sys.stdout.write(printed)
        # The NumPy reader: dtypes of the demo's 320x240 samples.
        self.assertRegex(printed, r"synth_000/\d{6}_\d{6} \(240, 320\) uint64 \d+")
        # The dependency-free reader (the last batch): stacked labels, int64 words, lists of
        # int32 matches.
        batch = namespace["batch"]
        self.assertEqual(tuple(batch["label01.npy"].shape), (4, 240, 320))
        self.assertEqual(str(batch["occ0.npy"].dtype), "torch.int64")
        self.assertEqual(len(batch["matches.npy"]), 4)
        self.assertEqual([str(m.dtype) for m in batch["matches.npy"]], ["torch.int32"] * 4)
        # ShardDataset + occgt's collate: a padded batch of 4 with its mask.
        self.assertRegex(printed, r"torch\.Size\(\[4, 1, 240, 320\]\) torch\.Size\(\[4, \d+, "
                                  r"2\]\) torch\.Size\(\[4, \d+\]\) torch\.int64")
        self.assertIn("torch.Size([4, 240, 320]) torch.int64 4", printed)
        self.assertRegex(printed, r"demo \[\('demo-000000.tar', 8\), \('demo-000001.tar', 8\), "
                                  r"\('demo-000002.tar', 8\)\]")
        self.assertRegex(printed, r"24 pairs, \d+ with more than 5 % of image 0 occluded in 1")
        self.assertIn("uint16 (24, 4) (24, 12) ['synth_000', 'synth_001']", printed)

    def check_json(self, doc: Dict[str, Any], where: str) -> None:
        """The index.json example has the keys of the real file, shard entries too."""
        with open(os.path.join("out", "demo", "index.json")) as f:
            real = json.load(f)
        self.assertEqual(sorted(doc), sorted(real), where)
        self.assertEqual(doc["__kind__"], real["__kind__"], where)
        self.assertEqual(sorted(doc["shardlist"][0]), sorted(real["shardlist"][0]), where)

    def check_folder(self, text: str, where: str) -> None:
        """Every file and folder the layout names exists in the split (shards by pattern)."""
        names = re.findall(r"^  (\S+)", text, flags=re.M)  # not the continuation lines
        split = os.path.join("out", "demo")
        for name in names:
            if name.endswith(".tar"):
                self.assertRegex(name, r"^[a-z]+-\d{6}\.tar$", where)
                self.assertTrue(os.path.exists(os.path.join(split, "demo-000000.tar")), where)
            else:
                self.assertTrue(os.path.exists(os.path.join(split, name)), f"{where}: {name}")
        self.assertEqual(names[1:], ["index.json", "pairs.jsonl", "summary.json", "parts/"],
                         where)


if __name__ == "__main__":
    unittest.main(verbosity=2)
