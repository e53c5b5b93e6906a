"""hystloop.read_log on the golden log (tests/data) and damaged copies of it, against what
hystloop-export (the same reader: tools/report) writes for the same files."""

import os
import glob
import struct
import unittest

import numpy as np

import hystloop
from tool_support import TempDirTest, run, tool

SENSOR_UNITS = {"seq": "1", "t_s": "s", "u_V": "V", "u_ff_V": "V", "u_fb_V": "V", "y_ref_m": "m", "y_m": "m",
                "flags": "1", "axis": "1"}
SYNC = 0xEDA1DA01


def golden():
    path = os.path.join(os.environ.get("HYSTLOOP_TEST_DATA", ""), "golden-loop.lcmlog")
    if not os.path.exists(path):
        raise unittest.SkipTest("no golden log (HYSTLOOP_TEST_DATA)")
    return path


def read_bytes(path):
    with open(path, "rb") as f:
        return f.read()


def fingerprint(lcm_type):
    """The type's LCM fingerprint, from the header lcm-gen made in the build tree."""
    headers = glob.glob(os.path.join(os.environ.get("HYSTLOOP_BUILD_DIR", ""), "**", f"{lcm_type}.hpp"),
                        recursive=True)
    if not headers:
        raise unittest.SkipTest(f"no generated {lcm_type}.hpp (HYSTLOOP_BUILD_DIR)")
    with open(headers[0], encoding="utf-8") as f:
        base = int(f.read().split("uint64_t hash = ")[1].split("LL")[0], 16)
    return ((base << 1) & (2**64 - 1)) | (base >> 63)


def events(data):
    """(offset, channel, payload) of every event of an intact log."""
    out, i = [], 0
    while i < len(data):
        sync, _, _, clen, dlen = struct.unpack(">IqqII", data[i:i + 28])
        assert sync == SYNC
        out.append((i, data[i + 28:i + 28 + clen].decode(), data[i + 28 + clen:i + 28 + clen + dlen]))
        i += 28 + clen + dlen
    return out


class LogTest(TempDirTest):
    def export(self, log):
        """hystloop-export's HDF5 of `log` (x axis), read back with h5py."""
        try:
            import h5py  # noqa: F401  (python3-h5py)
        except ImportError:
            self.skipTest("no h5py")
        out = self.path(os.path.basename(log) + ".h5")
        run([tool("HYSTLOOP_EXPORT_EXE"), "--hdf5", out, "--quiet", log])
        return out

    def assertSameAsExport(self, log_path, log):
        import h5py
        with h5py.File(self.export(log_path), "r") as f:
            for channel in ("HX_SENSOR", "HX_COMMAND", "HX_STATUS"):
                ours = log[channel]
                self.assertEqual(ours.rows, f[channel].attrs["rows"], channel)
                for name in f[channel]:
                    theirs = f[channel][name]
                    if "count_column" in theirs.attrs or "per_row" in theirs.attrs:
                        continue  # ragged: compared through the counters
                    mine = ours[name]
                    if theirs.dtype.kind == "f":
                        self.assertBitEqual(mine, theirs[()], f"{channel}.{name}")
                    elif theirs.dtype.kind in "iu":
                        np.testing.assert_array_equal(mine, theirs[()], f"{channel}.{name}")
                    if "units" in theirs.attrs:
                        self.assertEqual(ours.units[name], theirs.attrs["units"], f"{channel}.{name}")

    def test_golden_log_as_the_report_reads_it(self):
        path = golden()
        log = hystloop.read_log(path, axis=0)
        self.assertEqual(log.warnings, [])
        sensor = log["HX_SENSOR"]
        for name, unit in SENSOR_UNITS.items():
            self.assertEqual(sensor.units[name], unit, name)
        self.assertEqual(np.unique(np.diff(sensor["seq"])).tolist(), [1])
        self.assertTrue(np.all(sensor["axis"] == 0))
        self.assertSameAsExport(path, log)
        # every axis (None): a one-axis log has x only, the same rows
        every = hystloop.read_log(path)
        for name in SENSOR_UNITS:
            np.testing.assert_array_equal(every["SENSOR"][name], sensor[name])
        self.assertEqual(hystloop.read_log(path, axis=1)["HX_SENSOR"].rows, 0)
        status = log["HX_STATUS"]
        self.assertGreater(len(status.counters), 0)
        for name, values in status.counters.items():
            self.assertEqual(len(values), status.rows, name)
        self.assertEqual(len(status["counter_values"]), status.rows)
        ranged = hystloop.read_log(path, axis=0, from_s=0.1, to_s=0.2, channels=["SENSOR"])
        self.assertEqual(list(ranged.channels), ["HX_SENSOR"])
        t = ranged["SENSOR"]["t_s"]
        self.assertTrue(np.all((t >= 0.1) & (t <= 0.2)) and len(t) > 0)

    def test_truncated_and_damaged_copies(self):
        path = golden()
        data = read_bytes(path)
        full = hystloop.read_log(path, axis=0)
        cut = self.path("truncated.lcmlog")
        offset = events(data)[len(events(data)) // 2][0] + 40  # inside an event's payload
        with open(cut, "wb") as f:
            f.write(data[:offset])
        with self.assertWarnsRegex(RuntimeWarning, "not a complete event"):
            log = hystloop.read_log(cut, axis=0)
        self.assertEqual(len(log.warnings), 1)
        self.assertEqual(log.scans[0]["trailing_bytes"], 40)
        n = log["HX_SENSOR"].rows
        self.assertGreater(n, 0)
        self.assertLess(n, full["HX_SENSOR"].rows)
        for name in SENSOR_UNITS:
            self.assertBitEqual(log["HX_SENSOR"][name], full["HX_SENSOR"][name][:n], name)
        self.assertSameAsExport(cut, log)
        # junk between events: skipped and said, the rest read
        junk = self.path("junk.lcmlog")
        middle = events(data)[100][0]
        with open(junk, "wb") as f:
            f.write(data[:middle] + b"\x00garbage\xff" * 5 + data[middle:])
        log = hystloop.read_log(junk, axis=0, warn=False)
        self.assertIn("bytes between events are not events", log.warnings[0])
        self.assertEqual(log["HX_SENSOR"].rows, full["HX_SENSOR"].rows)

    def test_truth_and_axes_joined_by_tick(self):
        """The golden log made two-axis (y = x / 2) with HX_SIM_TRUTH after each sensor block:
        one row per tick and axis, y_true_m joined to the sensor rows by tick and axis."""
        sensor_hash, truth_hash = fingerprint("sensor_block_t"), fingerprint("sim_truth_t")
        data = read_bytes(golden())
        out = bytearray()
        number = 0

        def event(channel, utime, payload):
            nonlocal number
            name = channel.encode()
            number += 1
            return struct.pack(">IqqII", SYNC, number, utime, len(name), len(payload)) + name + payload

        for offset, channel, payload in events(data):
            utime = struct.unpack(">q", data[offset + 12:offset + 20])[0]
            if channel != "HX_SENSOR":
                out += event(channel, utime, payload)
                continue
            b_utime, seq, dt_s, depth, n_ticks, _, n = struct.unpack(">qqdiibi", payload[8:8 + 37])
            arrays = [np.frombuffer(payload, ">f8", n, 8 + 37 + 8 * n * k) for k in range(5)]
            flags = np.frombuffer(payload, ">i4", n, 8 + 37 + 40 * n)
            two = struct.pack(">Qqqdiibi", sensor_hash, b_utime, seq, dt_s, depth, n_ticks, 2, 2 * n)
            for a in arrays:
                two += np.column_stack([a, a / 2]).ravel().astype(">f8").tobytes()
            two += np.column_stack([flags, flags]).ravel().astype(">i4").tobytes()
            out += event(channel, utime, two)
            y_m = arrays[4]
            truth = struct.pack(">Qqqibi", truth_hash, b_utime, seq, n_ticks, 2, 2 * n)
            truth += np.column_stack([y_m - 1e-9, y_m / 2 - 1e-9]).ravel().astype(">f8").tobytes()
            out += event("HX_SIM_TRUTH", utime, truth)
        path = self.path("two-axes.lcmlog")
        with open(path, "wb") as f:
            f.write(out)
        x = hystloop.read_log(golden(), axis=0)["HX_SENSOR"]
        log = hystloop.read_log(path)
        self.assertEqual(log.warnings, [])
        sensor = log["HX_SENSOR"]
        self.assertEqual(sensor.rows, 2 * x.rows)
        np.testing.assert_array_equal(sensor["axis"], np.tile([0, 1], x.rows))
        np.testing.assert_array_equal(sensor["seq"], np.repeat(x["seq"], 2))
        self.assertBitEqual(sensor["y_m"][0::2], x["y_m"], "x")
        self.assertBitEqual(sensor["y_m"][1::2], x["y_m"] / 2, "y")
        self.assertBitEqual(sensor["t_s"][1::2], x["t_s"], "t_s")
        self.assertBitEqual(sensor["y_true_m"], sensor["y_m"] - 1e-9, "y_true_m")
        y_only = hystloop.read_log(path, axis=1)["HX_SENSOR"]
        for name in ("u_V", "u_ff_V", "y_m", "t_s", "y_true_m"):
            self.assertBitEqual(y_only[name], sensor[name][1::2], name)
        truth = log["HX_SIM_TRUTH"]
        self.assertEqual(truth.rows, sensor.rows)
        self.assertBitEqual(truth["t_s"], sensor["t_s"], "t_s")
        np.testing.assert_array_equal(truth["axis"], sensor["axis"])
        command = log["HX_COMMAND"]  # one-axis commands: x rows only
        self.assertTrue(np.all(command["axis"] == 0))

if __name__ == "__main__":
    unittest.main()
