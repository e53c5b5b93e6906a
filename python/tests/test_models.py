"""hystloop.Model against hystloop-model: every model forward and inverse bit for bit, the same
refusals with the same messages, parameter files both ways."""

import math
import unittest

import numpy as np

import hystloop
from tool_support import TempDirTest, read_csv, run, tool, write_csv

# A few non-default sets, so the comparison is not only of the defaults.
CUSTOM = {
    "mem": {"c1": 4.2e-9, "c2": 2.1e-12, "c3": 1.15},
    "pi": {"count": 7, "range_V": 180.0},
    "katalenic": {"k1": 30.0, "k2": 0.02, "output_shaping": {"gain": 4.1e-9}},
    "linear": {"gain": 5.5e-9, "offset": 1e-8},
    "banning": {},
}


def signal(n=4000):
    """A decaying sine with minor loops: reversals at many amplitudes."""
    t = np.arange(n) * 1e-4
    u = 220.0 * np.sin(2 * np.pi * 25.0 * t) * np.exp(-t * 3.0) + 20.0 * np.sin(2 * np.pi * 180.0 * t)
    return t, u


def flat(params, prefix=""):
    """The dict as --param NAME=VALUE assignments (nested dicts dotted)."""
    out = []
    for k, v in params.items():
        name = prefix + k
        if isinstance(v, dict):
            out += flat(v, name + ".")
        elif isinstance(v, (list, tuple)):
            out.append(f"{name}={','.join(repr(float(x)) for x in v)}")
        else:
            out.append(f"{name}={v!r}")
    return out


class ModelsTest(TempDirTest):
    def setUp(self):
        super().setUp()
        self.exe = tool("HYSTLOOP_MODEL_EXE")

    def tool_run(self, name, direction, t, x, params=(), params_file=None):
        column = "u" if direction == "forward" else "y_ref"
        csv = self.path(f"in-{name}-{direction}.csv")
        write_csv(csv, {"t": t, column: x})
        args = [self.exe, csv, f"--{direction}"]
        if name:
            args += ["--model", name]
        if params_file:
            args += ["--params-file", params_file]
        for p in params:
            args += ["--param", p]
        out = read_csv(run(args).stdout)
        return out["y" if direction == "forward" else "u"]

    def test_every_model_forward_and_inverse_bit_for_bit(self):
        self.assertEqual(set(hystloop.models()), set(CUSTOM), "a model the registry has and this test does not")
        t, u = signal()
        for name in hystloop.models():
            for params in ({}, CUSTOM[name]):
                with self.subTest(model=name, params=params):
                    m = hystloop.Model(name, params)
                    y = m.forward(u, t=t)
                    self.assertBitEqual(y, self.tool_run(name, "forward", t, u, flat(params)), f"{name} forward")
                    if not m.has_inverse:
                        continue
                    u_back = m.inverse(y)
                    self.assertBitEqual(u_back, self.tool_run(name, "inverse", t, y, flat(params)), f"{name} inverse")

    def test_yaml_both_ways(self):
        t, u = signal(1500)
        for name in hystloop.models():
            with self.subTest(model=name):
                m = hystloop.Model(name, CUSTOM[name])
                path = self.path(f"{name}.yaml")
                text = m.to_yaml(path)
                self.assertTrue(text.startswith(name + ":\n"), text)
                back = hystloop.Model.from_yaml(path)
                self.assertEqual(back.name, name)
                self.assertEqual(back.params, m.params)
                self.assertEqual(hystloop.Model(name, m.params).params, m.params)
                self.assertBitEqual(m.forward(u, t=t), self.tool_run("", "forward", t, u, params_file=path))

    def test_refusals_carry_the_tools_messages(self):
        t, u = signal(50)
        csv = self.path("refusal.csv")
        write_csv(csv, {"t": t, "u": u})
        cases = [
            ("mem", {"c3": -1.0}, ["c3=-1.0"], "c3"),  # the model's validation
            ("mem", {"c4": 1e-9}, ["c4=1e-09"], "c4"),  # unknown name, with a guess
            ("mem", {"c1": "abc"}, ["c1=abc"], "c1"),  # malformed value
            ("pi", {"count": 40}, ["count=40"], "count"),
            ("katalenic", {"input_shaping": {"kind": "cubic"}}, ["input_shaping.kind=cubic"], "input_shaping.kind"),
        ]
        for name, params, args, field in cases:
            with self.subTest(model=name, params=params):
                p = run([self.exe, csv, "--forward", "--model", name] + [a for x in args for a in ("--param", x)],
                        check=False)
                self.assertEqual(p.returncode, 2, p.stderr)
                tool_message = p.stderr.strip().removeprefix("hystloop-model: ")
                with self.assertRaises(hystloop.ParameterError) as e:
                    hystloop.Model(name, params)
                self.assertIsInstance(e.exception, ValueError)
                self.assertEqual(e.exception.field, field)
                message = str(e.exception)
                if tool_message.startswith("--param "):  # the origin: --param NAME=VALUE vs NAME=VALUE
                    tool_message = tool_message.split(": ", 1)[1]
                    message = message.split(": ", 1)[1]
                self.assertEqual(message, tool_message)
        p = run([self.exe, csv, "--forward", "--model", "mme"], check=False)
        with self.assertRaises(hystloop.ParameterError) as e:
            hystloop.Model("mme")
        self.assertEqual(str(e.exception), p.stderr.strip().removeprefix("hystloop-model: --model: "))
        self.assertIn("did you mean 'mem'", str(e.exception))

    def test_refusals_of_the_data(self):
        m = hystloop.Model("mem")
        with self.assertRaisesRegex(ValueError, r"u\[1\] = nan"):
            m.forward(np.array([0.0, math.nan]))
        with self.assertRaisesRegex(ValueError, "1-D"):
            m.forward(np.zeros((3, 2)))
        banning = hystloop.Model("banning")
        with self.assertRaisesRegex(ValueError, "has no inverse"):
            banning.inverse(np.zeros(3))
        with self.assertRaisesRegex(ValueError, "give t"):
            banning.forward(np.zeros(3))
        with self.assertRaisesRegex(ValueError, "does not increase"):
            banning.forward(np.zeros(3), t=np.array([0.0, 1e-4, 1e-4]))
        with self.assertRaises(TypeError):
            hystloop.Model("mem", c1=True)

    def test_inputs_of_any_layout(self):
        t, u = signal(600)
        m = hystloop.Model("mem")
        y = m.forward(u)
        self.assertBitEqual(m.forward(list(u)), y, "list")
        self.assertBitEqual(m.forward(np.ascontiguousarray(np.stack([u, u])[:, ::1][0])), y, "view")
        strided = np.repeat(u, 2)[::2]
        self.assertBitEqual(m.forward(strided), y, "strided")
        self.assertBitEqual(m.forward(u.astype(np.float32).astype(np.float64)),
                            m.forward(u.astype(np.float32)), "float32")
        self.assertEqual(len(m.forward(np.array([]))), 0)

    def test_help_names_units_and_defaults(self):
        info = hystloop.model_info("mem")
        self.assertEqual([p["name"] for p in info["parameters"]], ["c1", "c2", "c3"])
        self.assertEqual(info["parameters"][0]["unit"], "m/V")
        for f in (hystloop.Model.forward, hystloop.Model.inverse, hystloop.identify, hystloop.read_log):
            self.assertIn("[", f.__doc__)


if __name__ == "__main__":
    unittest.main()
