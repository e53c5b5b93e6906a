"""hystloop.identify_banning against hystloop-identify --model banning on the log of a short sine
series (recorded by hystloop_python_banning_log as tools/identify's series test records one: the
real compensator against the simulated Banning stage, no network): the same report, YAML and
refusals, the parameters to the last bit."""

import os
import re
import unittest

import hystloop
from tool_support import TempDirTest, run, tool


def without_solve_time(text):
    """The fit line's solver time in ms is the only figure that differs from run to run."""
    return re.sub(r"RMS, [0-9.]+ ms\n", "RMS, <t> ms\n", text)


class IdentifyBanning(TempDirTest):
    @classmethod
    def setUpClass(cls):
        cls._dir = __import__("tempfile").TemporaryDirectory(prefix="hystloop-python-banning-")
        cls.log = os.path.join(cls._dir.name, "series.lcmlog")
        run([tool("HYSTLOOP_BANNING_LOG_EXE"), cls.log])
        with open(cls.log, "rb") as f:
            data = f.read()
        # Cut short: after one usable loop (the fit refuses), and before any usable one.
        cls.one_loop = os.path.join(cls._dir.name, "one-loop.lcmlog")
        cls.no_loop = os.path.join(cls._dir.name, "no-loop.lcmlog")
        with open(cls.one_loop, "wb") as f:
            f.write(data[:1_200_000])
        with open(cls.no_loop, "wb") as f:
            f.write(data[:600_000])

    @classmethod
    def tearDownClass(cls):
        cls._dir.cleanup()

    def identify_tool(self, *args):
        return run([tool("HYSTLOOP_IDENTIFY_EXE"), "--model", "banning", *args], check=False)

    def test_same_fit_as_the_tool(self):
        p = self.identify_tool(self.log, "--out", self.path("b.yaml"))
        self.assertEqual(p.returncode, 0, p.stderr)
        r = hystloop.identify_banning(self.log)
        self.assertTrue(r.ok)
        self.assertTrue(r.stage_identified)
        out = r.experiments + r.report + "--- YAML\n" + r.yaml + "written to " + self.path("b.yaml") + "\n"
        self.assertEqual(without_solve_time(out), without_solve_time(p.stdout))
        with open(self.path("b.yaml"), encoding="utf-8") as f:
            written = f.read()
        self.assertEqual(written, "# written by hystloop-identify\n" + r.yaml)
        # The YAML's numbers are the shortest text that reads back exactly: the same doubles.
        values = dict(re.findall(r"^    (a|b|alpha|s_max|k|c): (\S+)", written, re.M))
        for name in ("a", "b", "alpha", "s_max", "k", "c"):
            self.assertEqual(float(values[name]).hex(), float(getattr(r, name)).hex(), name)
        self.assertEqual(r.params["hysteresis"]["alpha"], r.alpha)
        self.assertEqual(r.params["stage"]["k"], r.k)
        # The simulated stage's truth (deploy/config/bridge.yaml's banning section), as the tool's test.
        self.assertAlmostEqual(r.a / 8.58e-9, 1.0, delta=0.005)
        self.assertAlmostEqual(r.k / 1.17e8, 1.0, delta=0.02)
        self.assertEqual(len(r.points), 9)
        self.assertEqual(r.points[5]["kind"], "magnitude")
        r.to_yaml(self.path("py.yaml"))
        with open(self.path("py.yaml"), encoding="utf-8") as f:
            self.assertEqual(f.read(), written)
        self.assertIn("hystloop.BanningResult(a 8.58", repr(r))

    def test_a_list_of_logs_and_options_as_the_tool(self):
        p = self.identify_tool(self.log, "--max-late", "0.5", "--max-missing", "0.1")
        r = hystloop.identify_banning([self.log], max_late=0.5, max_missing=0.1)
        self.assertEqual(without_solve_time(r.experiments + r.report + "--- YAML\n" + r.yaml),
                         without_solve_time(p.stdout))

    def test_fit_refusals_as_the_tool(self):
        for log in (self.one_loop, self.no_loop):
            p = self.identify_tool(log)
            self.assertEqual(p.returncode, 1, p.stderr)
            with self.assertRaises(hystloop.FitError) as e:
                hystloop.identify_banning(log)
            self.assertEqual(p.stderr, f"hystloop-identify: {e.exception}\n")
            self.assertEqual(e.exception.status, "too_few_samples")
            result = e.exception.result
            self.assertFalse(result.ok)
            self.assertEqual(result.yaml, "")
            self.assertEqual(p.stdout, result.experiments + result.report)
            unchecked = hystloop.identify_banning(log, check=False)
            self.assertEqual((unchecked.status, unchecked.reason), (result.status, result.reason))

    def test_log_and_option_refusals_as_the_tool(self):
        golden = os.path.join(os.environ.get("HYSTLOOP_TEST_DATA", ""), "golden-loop.lcmlog")
        if not os.path.exists(golden):
            self.skipTest("no golden log")
        for log, kwargs, args in ((golden, {}, []), (self.log, {"axis": 1}, ["--axis", "y"])):
            p = self.identify_tool(log, *args)
            self.assertEqual(p.returncode, 2, p.stderr)
            with self.assertRaises(hystloop.ParameterError) as e:
                hystloop.identify_banning(log, **kwargs)
            self.assertEqual(p.stderr, f"hystloop-identify: {e.exception}\n")
        for kwargs in ({"max_late": 2.0}, {"max_missing": -0.1}, {"axis": 3}, {"dt_s": 0.0}, {"rig": "bad prefix"}):
            with self.assertRaises(hystloop.ParameterError) as e:
                hystloop.identify_banning(self.log, **kwargs)
            self.assertEqual(e.exception.field, next(iter(kwargs)))
        with self.assertRaises(hystloop.ParameterError):
            hystloop.identify_banning([])


if __name__ == "__main__":
    unittest.main()
