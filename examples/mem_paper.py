"""The MEM paper's workflow from Python, on a running rig (Strijbosch, Tiels and Oomen's experiment):

1. the identification experiment, 250 V sin(20 pi t) for 2 s with the servo off, recorded;
2. the memory-element model identified from it (hystloop.identify, the same fit as hystloop-identify);
3. the set sent to the compensator, which tracks the paper's reference y_d = -1.6 um cos(2 pi t)
   with the MEM's inverse, then with linear feedforward, the servo still off;
4. the tracking error of each against the stage's true position, as a table and a plot.

    ./deploy/hystloop up logger bridge compensator        # the simulated rig, no re-identifier
    ./deploy/hystloop python examples/mem_paper.py        # --out DIR, --seconds S per mode

A running re-identifier would replace the identified set with its own refits while the two
feedforwards are compared: the example refuses to start beside one.

The servo's gains and the compensator's mode are put back whatever happens. Writes
mem_paper.png and mem_paper.csv to --out (default out/mem-paper).
"""

import argparse
import os
import sys

import numpy as np

import hystloop

EXPERIMENT = dict(amplitude_V=250.0, frequency_Hz=10.0, duration_s=2.0)  # the paper's input
REFERENCE = dict(shape="cosine", amplitude_m=-1.6e-6, frequency_Hz=1.0)  # eq. (24)


def experiment_ticks(rec):
    """The experiment's ticks of axis x: no reference (the compensator drives u itself), u moving."""
    x = rec["axis"] == 0
    mask = x & np.isnan(rec["y_ref_m"]) & (rec["u_V"] != 0.0)
    return rec["t_s"][mask], rec["u_V"][mask], rec["y_m"][mask]


def tracking(rig, mode, seconds):
    """Tracks the reference in `mode` for `seconds` after a second to settle: t [s], error [m] of
    the true position (the measured one on a real stage), and its RMS [m]."""
    rig.set_mode(mode)
    rig.record(1.0)  # the change of mode and the blend pass
    rec = rig.record(seconds)
    x = (rec["axis"] == 0) & np.isfinite(rec["y_ref_m"])
    y = np.where(np.isfinite(rec["y_true_m"]), rec["y_true_m"], rec["y_m"])
    e = rec["y_ref_m"][x] - y[x]
    return rec["t_s"][x] - rec["t_s"][x][0], e, float(np.sqrt(np.mean(e * e)))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default="out/mem-paper", help="folder for mem_paper.png and mem_paper.csv")
    ap.add_argument("--seconds", type=float, default=4.0, help="tracking time per mode [s] (default 4)")
    ap.add_argument("--timeout", type=float, default=5.0, help="each request's timeout [s]")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)

    rig = hystloop.Rig(timeout=args.timeout)
    status = rig.status()
    missing = [p for p in ("bridge", "compensator") if p not in status]
    if missing:
        sys.exit(f"mem_paper: no {' or '.join(missing)} on {rig.url}: start a rig "
                 "(./deploy/hystloop up logger bridge compensator)")
    if any(p.startswith("reidentifier") for p in status):
        sys.exit("mem_paper: a re-identifier is running: its refits would replace the identified set during the "
                 "comparison; stop it (./deploy/hystloop down reidentifier) and run again")
    counters = status["bridge"]["counters"]
    gains = {k: counters.get(f"servo_{c}", 0) / s for k, c, s in
             (("kp", "kp_ppm", 1e6), ("ki", "ki_ppm_per_s", 1e6), ("kd", "kd_ps", 1e12))}
    mode_before = status["compensator"]["counters"].get("mode", 2)
    modes = {0: "off", 1: "linear", 2: "mem", 3: "pi", 4: "katalenic"}

    rig.arm()
    rig.set_gains(kp=0.0, ki=0.0, kd=0.0)  # feedforward alone, as in the paper
    try:
        print("mem_paper: identification experiment, 250 V sin(20 pi t) for 2 s")
        rig.experiment(**EXPERIMENT)
        rec = rig.record(EXPERIMENT["duration_s"] + 0.3)
        t, u, y = experiment_ticks(rec)
        if len(t) < 1000:
            sys.exit(f"mem_paper: the experiment gave {len(t)} samples: did it run? ({rig.status()})")
        fit = hystloop.identify(t, u, y, model="mem")
        p = fit.params
        print(f"mem_paper: MEM identified from {len(t)} samples: c1 {p['c1']:.4g} m/V, c2 {p['c2']:.4g}, "
              f"c3 {p['c3']:.4g}, residual {fit.residual_m * 1e9:.2f} nm RMS")
        # The reference first: the compensator swaps a set in at a reversal of the motion.
        print("mem_paper: the compensator " + rig.set_trajectory(**REFERENCE, blend_s=0.5))
        rig.set_mode("mem")
        version = rig.set_params(p["c1"], p["c2"], p["c3"], residual_m=fit.residual_m)
        print(f"mem_paper: the compensator uses parameters v{version}")

        results = {}
        for mode in ("mem", "linear"):
            results[mode] = tracking(rig, mode, args.seconds)
            print(f"mem_paper: {mode:6s} feedforward: {results[mode][2] * 1e9:7.2f} nm RMS")
    finally:
        rig.set_gains(**gains)
        rig.set_mode(modes.get(mode_before, "mem"))

    with open(os.path.join(args.out, "mem_paper.csv"), "w") as f:
        f.write("feedforward,rms_nm,max_nm\n")
        for mode, (_, e, rms) in results.items():
            f.write(f"{mode},{rms * 1e9:.4f},{np.max(np.abs(e)) * 1e9:.4f}\n")

    import matplotlib
    matplotlib.use(os.environ.get("MPLBACKEND", "Agg"))
    import matplotlib.pyplot as plt

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4))
    ax1.plot(u, y * 1e6, ".", ms=1, label="measured")
    ax1.plot(u, fit.fitted.forward(u) * 1e6, lw=0.8, label="MEM identified")
    ax1.set_xlabel("u [V]")
    ax1.set_ylabel("y [um]")
    ax1.set_title("the identification experiment")
    ax1.legend()
    for mode, (te, e, rms) in results.items():
        ax2.plot(te, e * 1e9, lw=0.7, label=f"{mode}: {rms * 1e9:.1f} nm RMS")
    ax2.set_xlabel("t [s]")
    ax2.set_ylabel("y_d - y [nm]")
    ax2.set_title("tracking -1.6 um cos(2 pi t), servo off")
    ax2.legend()
    fig.tight_layout()
    path = os.path.join(args.out, "mem_paper.png")
    fig.savefig(path, dpi=110)
    print(f"mem_paper: wrote {path}")
    if not results["mem"][2] < results["linear"][2]:
        sys.exit("mem_paper: the MEM's inverse did not track better than linear feedforward")


if __name__ == "__main__":
    main()
