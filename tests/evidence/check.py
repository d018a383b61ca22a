"""Self-check of the evidence tool; prints the real-log acceptance table.

    python3 tests/evidence/check.py [--cli PATH/navguard.mjs]

Needs `pip install pymavlink pyulog` and a built pkg/ (default: this
worktree's pkg/bin/navguard.mjs, else /work/main's). Exits non-zero only
when the tool is broken:
  * the independent readers and navguard's readers disagree on the number
    of GPS fix epochs of a log (beyond EPOCH_TOL);
  * the tool no longer reproduces facts of the shared logs that the data
    README states (Loiter_RTL.bin loss at 97.0-103.4 s with ERR glitch and
    failsafe, its logging pause, the 0.92 boot clock of the 2014 Erle logs);
  * a verdict rule gives the wrong class on a hand-built case;
  * an interval is left without a verdict.
The detector's acceptance figures are printed, never asserted (yet).
"""
import argparse
import copy
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

EPOCH_TOL = 0.01  # share of a log's GPS epochs (at least 2)
failures = []


def check(cond, msg):
    if not cond:
        failures.append(msg)
        print("FAIL", msg)


def rule_cases(E):
    """Verdict rules on hand-built evidence: one case per class."""
    facts = {"hacc_median": 1.0, "clock_ratio": 1.0, "losses": [], "gps_t": [0.0], "gps_status": [3]}
    import numpy as np
    facts["gps_t"], facts["gps_status"] = np.array([0.0]), np.array([3])
    base = {"start": 100.0, "end": 101.0, "dur": 1.0, "kind": "residual", "driver": "gps_position", "n_gps": 5,
            "status_min": 3, "sats_min": 9, "hdop_max": 1.2, "hacc_max": 1.0, "sacc_max": 0.3, "spd_max": 2.0,
            "gap": None, "errs": [], "err_active": [], "ekf": {"sv": 0.2, "sp": 0.3, "sh": 0.1}, "acc_std": [0.2] * 3,
            "vibe": None, "tilt_max": 10.0, "height": {}, "agl": 20.0}
    cases = []
    c = copy.deepcopy(base)
    cases.append(("healthy", c, "FALSE"))
    c = copy.deepcopy(base)
    c["status_min"] = 1
    cases.append(("status drop", c, "TRUE"))
    c = copy.deepcopy(base)
    c["err_active"] = ["GPS/2 (GPS glitch)"]
    cases.append(("ERR glitch", c, "TRUE"))
    c = copy.deepcopy(base)
    c["hacc_max"] = 9.0
    cases.append(("hAcc jump", c, "TRUE"))
    c = copy.deepcopy(base)
    c["ekf"]["sv"] = 1.5
    cases.append(("EKF ratio", c, "TRUE"))
    c = copy.deepcopy(base)
    c["acc_std"] = [1.0, 1.0, 7.8]
    cases.append(("vibration", c, "UNCLEAR"))
    c = copy.deepcopy(base)
    c.update(kind="gps_outage", gap={"from": 100.0, "to": 100.6, "boot": 0.6, "tow": 0.6, "st": (3, 3),
                                     "sats": (9, 9), "bad_between": False})
    cases.append(("logger gap", c, "UNCLEAR"))
    c = copy.deepcopy(base)
    c.update(kind="gps_outage", gap={"from": 100.0, "to": 100.6, "boot": 0.6, "tow": 0.6, "st": (3, 3),
                                     "sats": (9, 9), "bad_between": False}, err_active=["GPS/2 (GPS glitch)"])
    cases.append(("logger gap under a glitch episode", c, "UNCLEAR"))
    for name, ev, want in cases:
        got, why = E.verdict(ev, facts)
        check(got == want, f"rule '{name}': {got} ({why}), want {want}")


def main():
    try:
        import pymavlink  # noqa: F401
        import pyulog  # noqa: F401
    except ImportError as e:
        sys.exit(f"evidence check: {e}; run `python3 -m pip install pymavlink pyulog`")
    import evidence as E
    import run_all as R

    here = os.path.join(E.ROOT, "pkg", "bin", "navguard.mjs")
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cli", default=here if os.path.exists(here) else E.DEFAULT_CLI)
    ap.add_argument("--data", default=os.path.join(E.ROOT, "..", "shared", "data"))
    args = ap.parse_args()

    rule_cases(E)
    runs, min_loss = R.run(args.cli, os.path.normpath(args.data))
    check(len(runs) >= 13, f"expected the 13 shared logs, found {len(runs)}")
    for r in runs:
        want, got = r["facts"]["gps_fix_epochs"], r["report"].get("gpsEpochs", 0)
        tol = max(2, EPOCH_TOL * want)
        check(abs(want - got) <= tol, f"{r['name']}: GPS epochs independent {want}, navguard {got}")
        for ev in r["evs"]:
            check(ev["verdict"] in ("TRUE", "FALSE", "UNCLEAR") and ev["reason"],
                  f"{r['name']} [{ev['start']:.2f}]: no verdict")
    by = {os.path.basename(r["path"]): r for r in runs}
    lr = by.get("Loiter_RTL.bin")
    check(lr is not None, "Loiter_RTL.bin not found")
    if lr:
        f = lr["facts"]
        # README: fix lost 97.0 to 103.4 s (103.40 is the first record after it, status 1
        # "no fix"; the first 3D record is 103.66); the first status-0 record is 98.22.
        check(any(abs(a - 97.0) < 0.1 and abs(fb - 98.22) < 0.05 and abs(b - 103.66) < 0.05
                  for a, b, fb in f["losses"]), f"Loiter_RTL loss 97.0-103.66 s not read: {f['losses']}")
        eps = f["err_episodes"]
        check(any(abs(a - 98.22) < 0.05 and "GPS glitch" in n for a, _, n in eps), f"Loiter_RTL ERR glitch: {eps}")
        check(any(abs(a - 101.99) < 0.05 and "GPS failsafe" in n for a, _, n in eps), f"Loiter_RTL failsafe: {eps}")
        check(any(abs(p - 51.4) < 0.3 and abs(q - 73.8) < 0.3 for p, q in f["pauses"]),
              f"Loiter_RTL logging pause 51.4-73.8 s: {f['pauses']}")
    for name, r in by.items():
        if name.startswith(("erle_", "Loiter")):
            cr = r["facts"]["clock_ratio"]
            check(cr is not None and abs(cr - 0.923) < 0.005, f"{name}: boot/GPS clock {cr}, README says ~0.92")
    print(f"shortest real loss {min_loss:.2f} s")
    R.print_table(runs)
    print(f"evidence check: {'FAILED, ' + str(len(failures)) + ' problem(s)' if failures else 'ok'}")
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
