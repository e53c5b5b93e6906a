"""Every tick of a running rig for a while, from Python, and whether the rig noticed: the ticks
recorded, any missing, and the bridge's late ticks before, after, and over a loop of status() calls.

    ./deploy/hystloop up
    ./deploy/hystloop python examples/record.py            # --seconds S (default 10), --polls N (5)
"""

import argparse
import sys

import numpy as np

import hystloop


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seconds", type=float, default=10.0, help="how long to record [s] (default 10)")
    ap.add_argument("--polls", type=int, default=5, help="status() calls after it (default 5)")
    args = ap.parse_args()

    rig = hystloop.Rig()
    status = rig.status()
    if "bridge" not in status:
        sys.exit(f"record: no bridge on {rig.url}: start a rig (./deploy/hystloop up)")
    late_before = status["bridge"]["late"]
    r = rig.record(args.seconds)
    late_after = rig.status()["bridge"]["late"]
    late_polled = late_after
    for _ in range(args.polls):
        late_polled = rig.status(listen=1.1)["bridge"]["late"]
    in_order = all(np.all(np.diff(r["seq"][r["axis"] == a]) == 1) for a in range(r["axes"]))
    print(f"record({args.seconds:g}): {len(r['seq'])} ticks of {r['axes']} axis(es), missing {r['missing_ticks']}, "
          f"in order {in_order}, with truth {np.count_nonzero(np.isfinite(r['y_true_m']))}; bridge late ticks "
          f"{late_before} before, {late_after} after, {late_polled} after {args.polls} status() calls")
    if r["missing_ticks"] or not in_order:
        sys.exit("record: ticks were missing or out of order")


if __name__ == "__main__":
    main()
