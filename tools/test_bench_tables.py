#!/usr/bin/env python3
"""Tests of tools/bench_tables.py on real reports of small runs (tools/testdata/bench, written by
`chambre bench ... --json` at commit 2c31bb8 on lavapipe), and of BENCHMARKS.md itself.

  python3 tools/test_bench_tables.py
"""
import os
import re
import sys
import tempfile
import unittest

TOOLS = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(TOOLS)
sys.path.insert(0, TOOLS)

import bench_tables  # noqa: E402

DATA = os.path.join(TOOLS, "testdata", "bench")


def block(name):
    return dict(bench_tables.render_all(DATA))[name]


class Tables(unittest.TestCase):
    def test_build_table_is_the_report_with_its_provenance(self):
        self.assertEqual(block("build"), [
            "`chambre bench build --mesh scenes/meshes/bunny-npm-lowres.obj --runs 1 "
            "--json bench/build.json`",
            "",
            "Commit `2c31bb8`, 2026-11-27; 2 CPU threads (Intel(R) Xeon(R) Processor); adapter: "
            "llvmpipe (LLVM 15.0.6, 256 bits) (Vulkan, Cpu; driver llvmpipe Mesa 22.3.6 "
            "(LLVM 15.0.6)).",
            "",
            "| preset | build ms | nodes | depth | SAH cost | BVH MiB |",
            "|---|---|---|---|---|---|",
            "| fastest | 0.8 (0.8–0.8) | 7347 | 19 | 29.9 | 0.2 |",
            "| very_fast | 1.3 (1.3–1.3) | 1731 | 15 | 33.0 | 0.1 |",
            "| fast | 1.6 (1.6–1.6) | 1703 | 15 | 30.7 | 0.1 |",
            "| medium | 2.2 (2.2–2.2) | 1631 | 15 | 31.0 | 0.1 |",
            "| slow | 4.4 (4.4–4.4) | 1675 | 14 | 30.0 | 0.1 |",
            "| very_slow | 10.1 (10.1–10.1) | 1695 | 16 | 28.3 | 0.1 |",
        ])

    def test_frame_table_has_a_column_per_backend_with_its_speed_up_over_the_cpu(self):
        lines = block("frame")
        self.assertEqual(lines[4], "| scene | size x spp | triangles | cpu ms | cpu-general ms | "
                         "gpu-mega ms | gpu-mega-general ms | gpu-wave ms | "
                         "gpu-wave-general ms |")
        self.assertEqual(lines[6], "| spheres | 24x16 x 1 | 0 | 0.2 | 0.2 (1.15x) | 1.0 (0.26x) "
                         "| 4.8 (0.05x) | 1.8 (0.14x) | 1.9 (0.13x) |")
        self.assertEqual(len(lines), 8)

    def test_rays_rows_carry_the_checksum_and_the_cwbvh_traffic(self):
        lines = block("rays")
        self.assertIn("| coherent | closest | cpu (2 threads) | CWBVH | 0.59 (0.59–0.59) | 1 "
                      "| 79 | 9.424558e1 |", lines)
        self.assertIn("| incoherent | any | cpu (2 threads) | wide, packets of 16 (CPU) | "
                      "7.73 (7.73–7.73) | - | 128 | 0.000000e0 |", lines)
        # Every backend and layout agrees on the hits of each set.
        hits = {}
        for line in lines[6:]:
            cells = [c.strip() for c in line.strip("|").split("|")]
            hits.setdefault(cells[0], set()).add(cells[6])
        self.assertEqual(hits, {"coherent": {"79"}, "incoherent": {"128"}})

    def test_the_fermat_summary_takes_subdivision_4(self):
        self.assertEqual(block("fermat")[-1], "| sphere | 1.40 | 24.64 | 17.6x | 733/777 | 0.000 | "
                         "0.007 | 0.083 | 0.128 | 0.0798 |")

    def test_gpu_reports_come_from_the_gpu_folder(self):
        frames = block("gpu-frames")
        self.assertIn("bench/gpu/frame_dragon.json", frames[0])
        self.assertEqual(frames[-1], "| dragon | 32x32 x 2 | 871306 | 95.0 | 109.2 |")
        self.assertNotIn("gpu-peers", dict(bench_tables.render_all(DATA)))

    def test_rust_exponents(self):
        self.assertEqual(bench_tables.exponent(1700087.2), "1.700087e6")
        self.assertEqual(bench_tables.exponent(0.0), "0.000000e0")
        self.assertEqual(bench_tables.exponent(9.6e-5), "9.600000e-5")


class Update(unittest.TestCase):
    TEXT = ("# B\n\n<!-- bench:build -->\nold build table\n<!-- /bench:build -->\n\n"
            "<!-- bench:frame-motion -->\nkept as it is\n<!-- /bench:frame-motion -->\n")

    def test_blocks_with_reports_are_made_anew_and_the_others_kept(self):
        text, made, kept = bench_tables.update(self.TEXT, "B.md", DATA)
        self.assertEqual((made, kept), (["build"], ["frame-motion"]))
        self.assertNotIn("old build table", text)
        self.assertIn("| very_slow | 10.1 (10.1–10.1) | 1695 | 16 | 28.3 | 0.1 |\n"
                      "<!-- /bench:build -->", text)
        self.assertIn("<!-- bench:frame-motion -->\nkept as it is\n<!-- /bench:frame-motion -->",
                      text)
        self.assertEqual(bench_tables.update(text, "B.md", DATA)[0], text)

    def test_an_unclosed_block_names_its_line(self):
        with self.assertRaisesRegex(bench_tables.BenchError, r"^B.md:3: table `build` has no "
                                    r"closing"):
            bench_tables.update("# B\n\n<!-- bench:build -->\nold\n", "B.md", DATA)

    def test_an_unknown_block_names_its_line(self):
        with self.assertRaisesRegex(bench_tables.BenchError, r"^B.md:1: unknown table `rayz`"):
            bench_tables.update("<!-- bench:rayz -->\n<!-- /bench:rayz -->\n", "B.md", DATA)

    def test_a_broken_report_names_its_file_and_line(self):
        with tempfile.TemporaryDirectory() as folder:
            with open(os.path.join(folder, "build.json"), "w") as f:
                f.write('{\n  "command": ,\n}\n')
            with self.assertRaisesRegex(bench_tables.BenchError, r"build.json:2: not JSON"):
                bench_tables.update(self.TEXT, "B.md", folder)

    def test_the_file_is_replaced_whole(self):
        with tempfile.TemporaryDirectory() as folder:
            path = os.path.join(folder, "B.md")
            with open(path, "w") as f:
                f.write(self.TEXT)
            bench_tables.main(["bench_tables.py", DATA, "--update", path])
            self.assertEqual(os.listdir(folder), ["B.md"])
            with open(path) as f:
                self.assertIn("| fastest | 0.8 (0.8–0.8) |", f.read())


class BenchmarksPage(unittest.TestCase):
    """BENCHMARKS.md holds today's figures: small, no dated notebook, a command per table."""

    def setUp(self):
        with open(os.path.join(ROOT, "BENCHMARKS.md"), encoding="utf-8") as f:
            self.text = f.read()

    def test_it_is_under_40_kb(self):
        self.assertLess(len(self.text.encode("utf-8")), 40 * 1024)

    def test_it_has_no_notebook_words_or_dated_headings(self):
        self.assertNotRegex(self.text.lower(), r"session")
        self.assertEqual(re.findall(r"^#+ .*20\d\d-\d\d-\d\d.*$", self.text, re.M), [])

    def test_every_block_is_known_and_its_table_follows_a_command_and_a_commit(self):
        _, made, kept = bench_tables.update(self.text, "BENCHMARKS.md", "/nonexistent")
        self.assertEqual(made, [])
        for name in kept:
            body = self.text.split(f"<!-- bench:{name} -->\n")[1].split(
                f"<!-- /bench:{name} -->")[0]
            if name == "gpu-peers" and "|" not in body:
                continue  # not measured yet: the block says which script fills it
            self.assertRegex(body.split("\n")[0], r"^`(chambre|CHAMBRE_BIN=\S+ )", name)
            self.assertRegex(body, r"[Cc]ommit `[0-9a-f]{7}`", name)
            self.assertRegex(body, r"\n\|", name)


if __name__ == "__main__":
    unittest.main()
