"""A scan line with learning, from Python, on a running rig: a 50 Hz triangle of 1 um (the fast axis
of a raster), tracked with learning off and then on; the tracking error of each, period by period.

    ./deploy/hystloop up
    ./deploy/hystloop python examples/scan_learning.py     # --out DIR, --seconds S, --axis x|y|z

Learning is switched off again at the end. Writes scan_learning.png and scan_learning.csv to --out
(default out/scan-learning).
"""

import argparse
import os
import sys

import numpy as np

import hystloop

LINE = dict(shape="triangle", amplitude_m=0.5e-6, frequency_Hz=50.0, shape_if_infeasible=True)


def error_per_period(rec, axis, period_s):
    """The RMS error [m] of each whole period of the reference on `axis` (true position where known)."""
    a = (rec["axis"] == axis) & np.isfinite(rec["y_ref_m"])
    y = np.where(np.isfinite(rec["y_true_m"]), rec["y_true_m"], rec["y_m"])[a]
    e = rec["y_ref_m"][a] - y
    n = int(round(period_s / rec["dt_s"]))
    periods = len(e) // n
    return np.sqrt(np.mean(e[: periods * n].reshape(periods, n) ** 2, axis=1)), e


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default="out/scan-learning", help="folder for scan_learning.png and .csv")
    ap.add_argument("--seconds", type=float, default=3.0, help="seconds with learning off, and on (default 3)")
    ap.add_argument("--axis", default="x", choices=list(hystloop.AXES), help="the axis scanned")
    args = ap.parse_args()
    axis = hystloop.AXES[args.axis]
    os.makedirs(args.out, exist_ok=True)

    rig = hystloop.Rig(timeout=5.0)
    if "compensator" not in rig.status():
        sys.exit(f"scan_learning: no compensator on {rig.url}: start a rig (./deploy/hystloop up)")
    rig.arm()
    period_s = 1.0 / LINE["frequency_Hz"]
    try:
        rig.learn("off")
        print(rig.set_trajectory(**LINE, blend_s=0.3, axis=axis))
        rig.record(0.5)  # the blend
        off, e_off = error_per_period(rig.record(args.seconds), axis, period_s)
        rig.learn("on")
        on, e_on = error_per_period(rig.record(args.seconds), axis, period_s)
    finally:
        rig.learn("off")
    last = on[-max(1, len(on) // 4):]  # the last quarter: learned
    print(f"scan_learning: 1 um triangle at 50 Hz on {args.axis}: learning off {np.mean(off) * 1e9:.2f} nm RMS, "
          f"on {np.mean(last) * 1e9:.2f} nm RMS once learned ({len(on)} periods)")
    with open(os.path.join(args.out, "scan_learning.csv"), "w") as f:
        f.write("period,learning,rms_nm\n")
        for i, v in enumerate(off):
            f.write(f"{i},off,{v * 1e9:.4f}\n")
        for i, v in enumerate(on):
            f.write(f"{len(off) + i},on,{v * 1e9:.4f}\n")

    import matplotlib
    matplotlib.use(os.environ.get("MPLBACKEND", "Agg"))
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 4))
    ax.plot(np.arange(len(off)), off * 1e9, "o-", ms=3, label="learning off")
    ax.plot(len(off) + np.arange(len(on)), on * 1e9, "o-", ms=3, label="learning on")
    ax.set_xlabel("period (20 ms)")
    ax.set_ylabel("RMS error per period [nm]")
    ax.set_title(f"1 um triangle at 50 Hz on {args.axis}")
    ax.legend()
    fig.tight_layout()
    path = os.path.join(args.out, "scan_learning.png")
    fig.savefig(path, dpi=110)
    print(f"scan_learning: wrote {path}")
    if not np.mean(last) < np.mean(off):
        sys.exit("scan_learning: learning did not lower the error")


if __name__ == "__main__":
    main()
