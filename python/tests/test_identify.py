"""hystloop.identify against hystloop-identify on the same CSV: the same fitted set to the last bit
(the YAML's numbers are exact), the same ranking, the same refusals."""

import re
import unittest

import numpy as np

import hystloop
from tool_support import TempDirTest, run, tool, write_csv


def record(n=6000, seed=1):
    """A MEM stage's response to a decaying sine with minor loops, with sensor noise."""
    t = np.arange(n) * 1e-4
    u = 230.0 * np.sin(2 * np.pi * 5.0 * t) * (1.0 - 0.6 * t / t[-1]) + 15.0 * np.sin(2 * np.pi * 47.0 * t)
    y = hystloop.Model("mem", c1=4.8e-9, c2=1.9e-12, c3=1.18).forward(u)
    y = y + np.random.default_rng(seed).normal(0.0, 2e-10, n)
    return t, u, y


class IdentifyTest(TempDirTest):
    def setUp(self):
        super().setUp()
        self.exe = tool("HYSTLOOP_IDENTIFY_EXE")

    def tool_fit(self, columns, *args):
        csv = self.path("record.csv")
        write_csv(csv, columns)
        out = self.path("fit.yaml")
        p = run([self.exe, csv, "--out", out] + list(args), check=False)
        return p, out

    def assertSameFit(self, result, out_yaml, stdout):
        self.assertTrue(result.ok, result)
        with open(out_yaml, encoding="utf-8") as f:
            text = f.read()
        self.assertEqual(text, "# written by hystloop-identify\n" + result.yaml)
        tool_set = hystloop.Model.from_yaml(out_yaml)
        self.assertEqual(tool_set.name, result.model)
        self.assertEqual(tool_set.params, result.params)  # floats compared exactly
        self.assertIn(f"{result.model}: {result.fitted.summary}", stdout)

    def test_each_model_as_the_tool_fits_it(self):
        t, u, y = record()
        for model, args in (("mem", []), ("mem", ["--form", "derivative"]), ("pi", ["--operators", "9"]),
                            ("katalenic", ["--katalenic-degree", "3"]), ("linear", []), ("mem", ["--decimate", "3"])):
            with self.subTest(model=model, args=args):
                p, out = self.tool_fit({"t": t, "u": u, "y": y}, "--model", model, *args)
                self.assertEqual(p.returncode, 0, p.stderr)
                kw = {}
                for i in range(0, len(args), 2):
                    kw[args[i][2:].replace("-", "_")] = args[i + 1] if args[i] == "--form" else int(args[i + 1])
                r = hystloop.identify(t, u, y, model=model, **kw)
                self.assertSameFit(r, out, p.stdout)
                m = re.search(r"fit: residual (\S+) nm RMS, (\d+) samples", p.stdout)
                self.assertEqual(m.group(1), f"{r.residual_m * 1e9:.4g}")
                self.assertEqual(int(m.group(2)), r.samples_used)
                self.assertTrue(np.isnan(r.heldout_rms_m))

    def test_auto_ranks_as_the_tool(self):
        t, u, y = record(9000, seed=2)
        p, out = self.tool_fit({"t": t, "u": u, "y": y}, "--model", "auto")
        self.assertEqual(p.returncode, 0, p.stderr)
        r = hystloop.identify(t, u, y)  # model="auto"
        self.assertSameFit(r, out, p.stdout)
        rows = re.findall(r"^\s+(\d+)\s+(\w+)\s+(\w+)\s+(\S+)\s+(\S+)\s+\S+", p.stdout, re.M)
        self.assertEqual([(m, s) for _, m, s, _, _ in rows], [(x.model, x.status) for x in r.ranking])
        for (_, _, _, train, held), x in zip(rows, r.ranking):
            self.assertEqual(train, f"{x.residual_m * 1e9:.4g}")
            self.assertEqual(held, f"{x.heldout_rms_m * 1e9:.4g}")
        self.assertIn(f"held out from sample {r.split_index} of {r.samples}; best: {r.model}", p.stdout)
        self.assertEqual(r.heldout_rms_m, r.ranking[0].heldout_rms_m)

    def test_no_fit_is_refused_with_the_tools_message(self):
        t = np.arange(2000) * 1e-4
        u = np.full_like(t, 10.0)  # constant input
        y = 5e-9 * u
        for model in ("mem", "auto"):
            with self.subTest(model=model):
                p, _ = self.tool_fit({"t": t, "u": u, "y": y}, "--model", model)
                self.assertEqual(p.returncode, 1, p.stderr)
                line = [l for l in p.stderr.splitlines() if "no fit" in l][0]
                with self.assertRaises(hystloop.FitError) as e:
                    hystloop.identify(t, u, y, model=model)
                self.assertEqual(str(e.exception), line.removeprefix("hystloop-identify: "))
                self.assertEqual(e.exception.status, e.exception.result.status)
                r = hystloop.identify(t, u, y, model=model, check=False)
                self.assertFalse(r.ok)
                self.assertEqual(f"no fit ({r.status}): {r.reason}", str(e.exception))

    def test_refused_inputs(self):
        t, u, y = record(500)
        with self.assertRaisesRegex(hystloop.ParameterError, "differ in length"):
            hystloop.identify(t, u, y[:-1])
        bad = u.copy()
        bad[7] = 2e4
        with self.assertRaisesRegex(hystloop.ParameterError, "sample 7: u = 20000 V is beyond the sanity bound"):
            hystloop.identify(t, bad, y)
        with self.assertRaises(hystloop.ParameterError) as e:
            hystloop.identify(t, u, y, model="nonsense")
        # The models it names are the library's, every one of them.
        self.assertIn("unknown here (one of auto, ", str(e.exception))
        for name in hystloop.models():
            if name != "banning":
                self.assertIn(name, str(e.exception))
        with self.assertRaisesRegex(hystloop.ParameterError, "operators"):
            hystloop.identify(t, u, y, model="pi", operators=40)
        p, _ = self.tool_fit({"t": t, "u": u, "y": y}, "--max-samples", "100")
        self.assertEqual(p.returncode, 2)
        with self.assertRaises(hystloop.ParameterError) as e:
            hystloop.identify(t, u, y, max_samples=100)
        self.assertEqual(str(e.exception), p.stderr.strip().removeprefix("hystloop-identify: "))


if __name__ == "__main__":
    unittest.main()
