#!/usr/bin/env python3
"""cmake/lcm_wire_layouts.py: the project's own types generate; a type the walker cannot check
stops the build (exit 1) with the file, line and field named. (That the generated layouts agree
with lcm-gen's encoding is tests/lcm/wire_layout_test.cpp's job.)"""
import pathlib
import subprocess
import sys
import tempfile
import unittest

ROOT = pathlib.Path(__file__).resolve().parents[2]
GENERATOR = ROOT / "cmake" / "lcm_wire_layouts.py"


def generate(out, *files):
    return subprocess.run([sys.executable, str(GENERATOR), str(out), "hystloop", *map(str, files)],
                          capture_output=True, text=True, check=False)


class WireLayoutGenerator(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.TemporaryDirectory()
        self.tmp = pathlib.Path(self.dir.name)

    def tearDown(self):
        self.dir.cleanup()

    def refused(self, body, *expected):
        lcm = self.tmp / "x_t.lcm"
        lcm.write_text("package hystloop;\n// a comment\nstruct x_t\n{\n" + body + "\n}\n")
        run = generate(self.tmp / "out", lcm)
        self.assertEqual(run.returncode, 1, run.stderr)
        self.assertFalse((self.tmp / "out").exists())
        for text in (f"{lcm}:",) + expected:
            self.assertIn(text, run.stderr)

    def test_the_projects_types_generate(self):
        run = generate(self.tmp, *sorted((ROOT / "lcmtypes").glob("*.lcm")))
        self.assertEqual(run.returncode, 0, run.stderr)
        defs = (self.tmp / "wire_layout_defs.inc").read_text()
        self.assertIn("::hystloop::sensor_block_t::getHash(), k_sensor_block_t, "
                      "::hystloop::sensor_block_t::MAX_VALUES", defs)
        self.assertIn("::hystloop::control_t::getHash(), k_control_t, 0", defs)

    def test_a_fixed_array_is_its_elements_and_a_boolean_one_byte(self):
        lcm = self.tmp / "x_t.lcm"
        lcm.write_text("package hystloop;\nstruct x_t\n{\n  boolean b[3]; /* x */ string s;\n}\n")
        self.assertEqual(generate(self.tmp, lcm).returncode, 0)
        self.assertIn("<WireField, 4> k_x_t{\n    WireField::kInt8,  // b[0]\n    WireField::kInt8,  // b[1]\n"
                      "    WireField::kInt8,  // b[2]\n    WireField::kString,  // s\n};",
                      (self.tmp / "wire_layout_defs.inc").read_text())

    def test_a_count_without_its_bound(self):
        self.refused("  int32_t n_a;\n  double a[n_a];", ":5:", "x_t.n_a", "const int32_t MAX_A")

    def test_a_count_that_is_not_int32(self):
        self.refused("  const int32_t MAX_A = 2;\n  int64_t n_a;\n  double a[n_a];", "x_t.n_a", "int32_t")

    def test_counts_with_two_bounds(self):
        self.refused("  const int32_t MAX_A = 2, MAX_B = 3;\n  int32_t n_a;\n  double a[n_a];\n"
                     "  int32_t n_b;\n  double b[n_b];", "MAX_A and MAX_B")

    def test_an_array_sized_by_an_earlier_count(self):
        self.refused("  const int32_t MAX_A = 2;\n  int32_t n_a;\n  const int32_t MAX_B = 3;\n"
                     "  int32_t n_b;\n  double b[n_b];\n  double a[n_a];", "x_t.a", "'n_b'")

    def test_a_nested_type_and_types_the_walker_has_no_field_for(self):
        for ftype in ("other_t", "hystloop.other_t", "float", "int16_t"):
            self.refused(f"  {ftype} y;", "x_t.y", f"'{ftype}'")

    def test_more_than_one_dimension(self):
        self.refused("  double a[2][3];", "x_t.a", "more than one dimension")

    def test_what_it_cannot_read(self):
        self.refused("  int32_t x junk;", "cannot read 'int32_t x junk'")


if __name__ == "__main__":
    unittest.main()
