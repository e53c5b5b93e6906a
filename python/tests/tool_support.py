"""What the Python tests share: the tools they compare against, CSV files written exactly."""

import os
import subprocess
import tempfile
import unittest

import numpy as np


def tool(name):
    """The built tool named by the environment (python/CMakeLists.txt sets it), or skip."""
    path = os.environ.get(name)
    if not path or not os.path.exists(path):
        raise unittest.SkipTest(f"{name} is not set to a built tool")
    return path


def write_csv(path, columns):
    """A header row, then one row per sample; repr() is the shortest text that reads back exactly."""
    names = list(columns)
    with open(path, "w", encoding="ascii") as f:
        f.write(",".join(names) + "\n")
        for row in zip(*(columns[n] for n in names)):
            f.write(",".join(repr(float(v)) for v in row) + "\n")


def read_csv(text):
    """The tool's CSV output as columns of float64 (its numbers read back exactly)."""
    lines = [l for l in text.splitlines() if l and not l.startswith("#")]
    names = lines[0].split(",")
    rows = [[float(v) for v in l.split(",")] for l in lines[1:]]
    data = np.array(rows, dtype=np.float64).reshape(len(rows), len(names))
    return {n: data[:, i] for i, n in enumerate(names)}


def run(args, check=True):
    p = subprocess.run(args, capture_output=True, text=True, timeout=600)
    if check and p.returncode != 0:
        raise AssertionError(f"{args} exited {p.returncode}: {p.stderr}")
    return p


class TempDirTest(unittest.TestCase):
    def setUp(self):
        self._tmp = tempfile.TemporaryDirectory(prefix="hystloop-python-")
        self.tmp = self._tmp.name

    def tearDown(self):
        self._tmp.cleanup()

    def path(self, name):
        return os.path.join(self.tmp, name)

    def assertBitEqual(self, a, b, what=""):
        a = np.ascontiguousarray(a, dtype=np.float64)
        b = np.ascontiguousarray(b, dtype=np.float64)
        self.assertEqual(a.shape, b.shape, what)
        diff = np.flatnonzero(a.view(np.uint64) != b.view(np.uint64))
        if diff.size:
            k = diff[0]
            self.fail(f"{what}: {diff.size} values differ, first at {k}: {a[k]!r} != {b[k]!r}")
