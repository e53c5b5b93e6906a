#!/usr/bin/env python3
"""Reads hystloop-export's files as a lab would, with h5py and scipy.io (export_tool_test runs it).

    read_export.py RUN.h5 RUN.mat Y_M_HEX...

Y_M_HEX: the HX_SENSOR y_m values the test logged, as float.hex() strings (exact). Prints "ok"
and exits 0, or names the first difference and exits 1.
"""
import sys

import h5py
import numpy as np
import scipy.io


def fail(why):
    print(why)
    sys.exit(1)


h5_path, mat_path, *hex_values = sys.argv[1:]
want = np.array([float.fromhex(v) for v in hex_values])

with h5py.File(h5_path, "r") as f:
    y = f["HX_SENSOR/y_m"][...]
    if y.dtype != np.float64 or y.tobytes() != want.tobytes():
        fail(f"h5py: HX_SENSOR/y_m is {y!r}, want {want!r}")
    if f["HX_SENSOR/y_m"].attrs["units"] != "m":
        fail(f"h5py: y_m units {f['HX_SENSOR/y_m'].attrs['units']!r}")
    if "2=mem" not in f["HX_COMMAND/mode"].attrs["legend"]:
        fail(f"h5py: HX_COMMAND/mode legend {f['HX_COMMAND/mode'].attrs['legend']!r}")
    if f.attrs["rig_prefix"] != "HX_":
        fail(f"h5py: rig_prefix {f.attrs['rig_prefix']!r}")
    names = [n.decode() for n in f["HX_STATUS/counter_names"][...]]
    if names[:2] != ["ticks", "rejected_nonfinite"]:
        fail(f"h5py: counter_names {names!r}")

m = scipy.io.loadmat(mat_path)
y = m["HX_SENSOR"]["y_m"][0, 0].ravel()
if y.dtype != np.float64 or y.tobytes() != want.tobytes():
    fail(f"scipy.io: HX_SENSOR.y_m is {y!r}, want {want!r}")
unit = m["HX_SENSOR_meta"]["units"][0, 0]["y_m"][0, 0][0]
if unit != "m":
    fail(f"scipy.io: HX_SENSOR_meta.units.y_m is {unit!r}")
legend = m["HX_SENSOR_meta"]["legend"][0, 0]["flags"][0, 0][0]
if "2=safe_state" not in legend:
    fail(f"scipy.io: flags legend {legend!r}")
print("ok")
