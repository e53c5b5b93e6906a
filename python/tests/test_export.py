"""hystloop.read_export against hystloop.read_log: the golden log exported by the built
hystloop-export in each format (HDF5, MAT level 5, MAT 7.3) reads back as read_log reads the log,
column for column, bit for bit, with the same units, descriptions and legends."""

import os
import unittest

import numpy as np

import hystloop
from tool_support import TempDirTest, run, tool

# Columns read_log adds that an export does not hold: the blocks' axis (the export is of one axis
# per tick row) and the simulated stage's truth (from HX_SIM_TRUTH).
READ_LOG_ONLY = {"axis", "y_true_m"}


class ReadExport(TempDirTest):
    def setUp(self):
        super().setUp()
        self.golden = os.path.join(os.environ.get("HYSTLOOP_TEST_DATA", ""), "golden-loop.lcmlog")
        if not os.path.exists(self.golden):
            self.skipTest("no golden log")
        self.export_exe = tool("HYSTLOOP_EXPORT_EXE")
        self.log = hystloop.read_log(self.golden, warn=False)

    def export(self, *args):
        run([self.export_exe, self.golden, "--quiet", *args])

    def assertSameValues(self, got, want, what):
        if isinstance(want, list):  # a ragged column: one array per row
            self.assertIsInstance(got, list, what)
            self.assertEqual(len(got), len(want), what)
            for r, (g, w) in enumerate(zip(got, want)):
                self.assertSameValues(g, w, f"{what}[{r}]")
            return
        self.assertEqual(got.dtype, want.dtype, what)
        if want.dtype == np.float64:
            self.assertBitEqual(got, want, what)
        else:
            self.assertEqual(got.shape, want.shape, what)
            self.assertTrue(np.array_equal(got, want), what)

    def assertSameAsLog(self, exp, fmt):
        self.assertEqual(exp.format, fmt)
        self.assertEqual(sorted(exp.channels), sorted(self.log.channels))
        for name, want in self.log.channels.items():
            got = exp[name]
            what = f"{fmt} {name}"
            self.assertEqual((got.name, got.type_name, got.rows, got.events, got.skipped),
                             (want.name, want.type_name, want.rows, want.events, want.skipped), what)
            self.assertEqual(set(got.keys()), set(want.keys()) - READ_LOG_ONLY, what)
            for c in got.keys():
                self.assertSameValues(got[c], want[c], f"{what}.{c}")
                self.assertEqual(got.units.get(c), want.units.get(c), f"{what}.{c} units")
                self.assertEqual(got.legends.get(c), want.legends.get(c), f"{what}.{c} legend")
                self.assertEqual(got.descriptions.get(c, ""), want.descriptions.get(c, ""), f"{what}.{c} description")
            self.assertEqual(sorted(got.counters), sorted(want.counters), what)
            for k in want.counters:
                self.assertBitEqual(got.counters[k], want.counters[k], f"{what} counter {k}")
        self.assertEqual(exp.run["rig_prefix"], "HX_")
        self.assertEqual(int(np.asarray(exp.run["time_zero_utime_us"]).ravel()[0]), self.log.t0_utime_us)
        self.assertIn("y_m", exp["SENSOR"])

    def test_hdf5(self):
        self.export("--hdf5", self.path("run.h5"))
        self.assertSameAsLog(hystloop.read_export(self.path("run.h5")), "hdf5")

    def test_mat5(self):
        self.export("--mat", self.path("run.mat"))
        self.assertSameAsLog(hystloop.read_export(self.path("run.mat")), "mat5")

    def test_mat73(self):
        self.export("--mat", self.path("run73.mat"), "--mat-version", "7.3")
        self.assertSameAsLog(hystloop.read_export(self.path("run73.mat")), "mat7.3")

    def test_config_and_refusal(self):
        cfg = os.path.join(os.path.dirname(self.golden), "golden-loop.compensator.yaml")
        self.export("--hdf5", self.path("c.h5"), "--mat", self.path("c.mat"), "--config", cfg, "--channel", "SENSOR")
        with open(cfg, encoding="utf-8") as f:
            text = f.read()
        for p in ("c.h5", "c.mat"):
            exp = hystloop.read_export(self.path(p))
            self.assertEqual(list(exp.channels), ["HX_SENSOR"])
            self.assertEqual(list(exp.config.values()), [text], p)
        with open(self.path("x.txt"), "w", encoding="ascii") as f:
            f.write("not an export\n")
        with self.assertRaises(ValueError):
            hystloop.read_export(self.path("x.txt"))
        with self.assertRaises(KeyError):
            hystloop.read_export(self.path("c.h5"))["COMMAND"]


if __name__ == "__main__":
    unittest.main()
