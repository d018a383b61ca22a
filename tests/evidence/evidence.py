"""Judge every fault interval navguard's audit raises on a log, with the
log's own independent evidence.

    python3 tests/evidence/evidence.py LOG [LOG...] [--cli PATH/navguard.mjs] [--json]

For each interval of `node CLI audit LOG --json` it prints what the receiver,
the autopilot and the other sensors recorded over the interval and +-5 s,
then a one-line verdict. The log is read with independent readers
(logread.py: pymavlink, pyulog, csv), never with navguard's.

Verdict rules, first match wins. C = the interval widened by CORE_MARGIN_S
on each side (plus, for outages, the GPS records that bound the gap):
  1 TRUE     the receiver reports a status drop in C (fix type < 3).
  2 TRUE     an autopilot error episode about the GPS/EKF/baro is active in C
             (ERR GPS glitch 11/2, GPS failsafe 7/1, EKF check 16/2, EKF
             failsafe 17/1, baro 18/2; PX4 vehicle_status.failsafe).
  3 TRUE     the receiver degrades in C: sats < 6, HDOP > 3, or hAcc above
             both HACC_JUMP_X times its flight median and HACC_ABS_M.
  4 UNCLEAR  vehicle upset: tilt above UPSET_DEG or an ERR CRASH_CHECK in the
             window (a flip or crash is not a sensor fault).
  5 UNCLEAR  vibration: an accelerometer 1 s standard deviation above
             VIB_STD_MS2 (snapshot IMU) or VIBE above VIBE_BAD; the IMU, and
             the EKF that integrates it, cannot judge the GPS or the baro.
  6 UNCLEAR  logger gap: an outage interval over a GPS record gap with a 3D
             fix on both sides and no status drop; the receiver time advanced
             across it (printed); records were lost, the fix was not.
  7 TRUE     the autopilot EKF's own test ratio exceeds 1 in C (SV velocity,
             SP position, SH height).
  8 FALSE    the receiver is healthy over C: 3D fix, sats >= 6, HDOP <= 3,
             hAcc <= HACC_ABS_M where known, EKF test ratios < 1 or absent,
             no autopilot error. A mechanism is named (see `mechanism`).
  9 UNCLEAR  anything else (e.g. no GPS record in C).
"""
import argparse
import json
import math
import os
import subprocess
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from logread import read_log  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
DEFAULT_CLI = "/work/main/pkg/bin/navguard.mjs"

CONTEXT_S = 5.0        # evidence window on each side of an interval
CORE_MARGIN_S = 0.5    # the interval itself, widened for record jitter
HACC_JUMP_X = 2.0
HACC_ABS_M = 5.0
VIB_STD_MS2 = 3.0      # snapshot accel 1 s std; the README's vibrating airframe is 3.6/3.7/7.8
VIBE_BAD = 30.0        # ArduPilot's guide: VIBE above 30 m/s^2 causes position problems
BARO_DEPART_M = 2.0    # baro minus GPS altitude change that counts as a departure
FAST_MS = 8.0          # horizontal speed of a manoeuvre / fast flight
TILT_DEG = 30.0
UPSET_DEG = 90.0       # tilt of a flip or crash; fixed-wing banks reach 80 deg
AFTER_OUTAGE_S = 7.0   # issue 14 item 11: false alarms 5-7 s after a degraded outage
NEAR_GROUND_M = 3.0    # baro (else GPS) altitude within this of the log's lowest: take-off, landing, ground
START_S = 30.0         # issue 14 item 4: the first 10-30 s while sigma is learnt
CLOCK_BAD = 0.02       # |boot/GPS clock ratio - 1| beyond which timing is suspect

# ArduCopter 3.x defines.h (ERROR_SUBSYSTEM_*, ERROR_CODE_*).
ERR_SUBSYS = {1: "MAIN", 2: "RADIO", 3: "COMPASS", 4: "OPTFLOW", 5: "FAILSAFE_RADIO", 6: "FAILSAFE_BATT",
              7: "FAILSAFE_GPS", 8: "FAILSAFE_GCS", 9: "FAILSAFE_FENCE", 10: "FLIGHT_MODE", 11: "GPS",
              12: "CRASH_CHECK", 13: "FLIP", 14: "AUTOTUNE", 15: "PARACHUTE", 16: "EKF_CHECK",
              17: "FAILSAFE_EKFINAV", 18: "BARO", 19: "CPU", 20: "FAILSAFE_ADSB", 21: "TERRAIN",
              22: "NAVIGATION", 23: "FAILSAFE_TERRAIN", 24: "EKF_PRIMARY"}
ERR_CODE = {(11, 2): "GPS glitch", (11, 0): "GPS glitch cleared", (7, 1): "GPS failsafe",
            (7, 0): "GPS failsafe resolved", (16, 2): "EKF bad variance", (16, 0): "EKF variance cleared",
            (17, 1): "EKF failsafe", (17, 0): "EKF failsafe resolved", (18, 2): "baro glitch",
            (18, 0): "baro glitch cleared", (12, 1): "crash", (12, 2): "loss of control"}
# (subsys, onset code): errors that speak about GPS/EKF/baro health; 0 ends them.
ERR_NAV = {(11, 2), (7, 1), (16, 2), (17, 1), (18, 2)}
# ArduCopter 3.x DATA_* event ids.
EV_NAME = {10: "ARMED", 11: "DISARMED", 15: "AUTO_ARMED", 16: "TAKEOFF", 17: "LAND_COMPLETE_MAYBE",
           18: "LAND_COMPLETE", 19: "LOST_GPS", 25: "SET_HOME", 28: "NOT_LANDED", 60: "EKF_ALT_RESET",
           62: "EKF_YAW_RESET"}


def err_name(sub, code):
    return f"{ERR_SUBSYS.get(sub, sub)}/{code}" + (f" ({ERR_CODE[(sub, code)]})" if (sub, code) in ERR_CODE else "")


# ---------------------------------------------------------------- navguard

def run_audit(cli, path):
    out = subprocess.run(["node", cli, "audit", path, "--json"], capture_output=True, text=True, timeout=600)
    if out.returncode not in (0, 1):
        raise RuntimeError(f"navguard audit {path}: exit {out.returncode}: {out.stderr.strip()}")
    return json.loads(out.stdout)


# ---------------------------------------------------------------- log-level facts

def nav_err_episodes(log):
    """[(start, end, name)] of GPS/EKF/baro error episodes (onset to the same
    subsystem's code 0, or the end of the log)."""
    eps, open_ = [], {}
    t_end = float(log.times[-1]) if len(log.times) else 0.0
    for t, sub, code in log.err:
        if (sub, code) in ERR_NAV and sub not in open_:
            open_[sub] = (t, err_name(sub, code))
        elif code == 0 and sub in open_:
            t0, nm = open_.pop(sub)
            eps.append((t0, t, nm))
    for sub, (t0, nm) in open_.items():
        eps.append((t0, t_end, nm))
    if log.has("fs"):
        t, f = log.s("fs", "t"), log.s("fs", "failsafe")
        on = None
        for ti, fi in zip(t, f):
            if fi and on is None:
                on = ti
            elif not fi and on is not None:
                eps.append((on, ti, "PX4 failsafe"))
                on = None
        if on is not None:
            eps.append((on, t[-1], "PX4 failsafe"))
    return sorted(eps)


def logging_pauses(log, min_gap=1.0):
    """[(start, end)] where no message at all was written (logger paused)."""
    t = log.times
    if len(t) < 2:
        return []
    d = np.diff(t)
    return [(float(t[i]), float(t[i + 1])) for i in np.nonzero(d > min_gap)[0]]


def receiver_losses(log):
    """[(start, end, first_bad)]: runs of GPS records with status < 3 after
    the first 3D fix; start = last good record before, end = first good after."""
    t, st = log.s("gps", "t"), log.s("gps", "status")
    good = st >= 3
    if not good.any():
        return []
    first = int(np.argmax(good))
    out, i = [], first
    while i < len(t):
        if not good[i]:
            j = i
            while j < len(t) and not good[j]:
                j += 1
            start = float(t[i - 1]) if i > 0 else float(t[i])
            end = float(t[j]) if j < len(t) else float(t[j - 1])
            out.append((start, end, float(t[i])))
            i = j
        else:
            i += 1
    return out


def clock_ratio(log, min_span=20.0):
    """Boot-clock seconds per receiver second (slope of boot t on GPS time), or None."""
    t, gt, st = log.s("gps", "t"), log.s("gps", "gtime"), log.s("gps", "status")
    ok = np.isfinite(gt) & (st >= 3)
    if ok.sum() < 10 or gt[ok].max() - gt[ok].min() < min_span:
        return None
    return float(np.polyfit(gt[ok] - gt[ok][0], t[ok], 1)[0])


def doppler_scale(log):
    """Median over 3D record pairs 0.1-0.5 s apart of (horizontal displacement
    from lat/lon) / (mean Doppler ground speed x boot dt), for speeds above
    5 m/s. 1 when the boot clock runs at GPS rate; 1/ratio when it is slow."""
    t, st, lat, lon, spd = (log.s("gps", k) for k in ("t", "status", "lat", "lon", "spd"))
    if len(lat) < 10:
        return None
    ok = (st[1:] >= 3) & (st[:-1] >= 3)
    dt = np.diff(t)
    r = 6371000.0
    dn = np.radians(np.diff(lat)) * r
    de = np.radians(np.diff(lon)) * r * np.cos(np.radians(lat[1:]))
    v = 0.5 * (spd[1:] + spd[:-1])
    sel = ok & (dt > 0.1) & (dt < 0.5) & (v > 5)
    if sel.sum() < 20:
        return None
    return float(np.median(np.hypot(dn, de)[sel] / (v[sel] * dt[sel])))


def record_gaps(log, min_gap=0.5):
    """GPS record gaps longer than min_gap (boot s) with their receiver-time advance."""
    t, gt, st, sats = (log.s("gps", k) for k in ("t", "gtime", "status", "sats"))
    out = []
    for i in np.nonzero(np.diff(t) > min_gap)[0]:
        adv = gt[i + 1] - gt[i] if (st[i] >= 3 and st[i + 1] >= 3) else math.nan
        out.append({"start": float(t[i]), "end": float(t[i + 1]), "boot": float(t[i + 1] - t[i]),
                    "tow": float(adv), "st": (int(st[i]), int(st[i + 1])), "sats": (int(sats[i]), int(sats[i + 1]))})
    return out


def accel_std_1s(log):
    """(bin_t, std[3]) of the accelerometer in 1 s bins (snapshot records)."""
    t = log.s("imu", "t")
    if len(t) < 10:
        return np.zeros(0), np.zeros((0, 3))
    a = np.vstack([log.s("imu", k) for k in ("ax", "ay", "az")]).T
    b = np.floor(t).astype(np.int64)
    starts = np.r_[0, np.nonzero(np.diff(b))[0] + 1]
    ends = np.r_[starts[1:], len(t)]
    keep = (ends - starts) >= 5
    bt = b[starts][keep].astype(float) + 0.5
    sd = np.array([a[s:e].std(axis=0) for s, e in zip(starts[keep], ends[keep])]).reshape(-1, 3)
    return bt, sd


def log_facts(log):
    t, st, sats, hdop = (log.s("gps", k) for k in ("t", "status", "sats", "hdop"))
    hacc = log.s("acc", "hacc")
    healthy = (st >= 3) & (sats >= 6) & ((hdop <= 3) | np.isnan(hdop))
    bt, sd = accel_std_1s(log)
    return {
        "gps_records": int(len(t)),
        "gps_fix_epochs": int((st >= 2).sum()),
        "healthy_share": float(healthy.mean()) if len(t) else math.nan,
        "fix3d_share": float((st >= 3).mean()) if len(t) else math.nan,
        "hacc_median": float(np.nanmedian(hacc)) if len(hacc) and np.isfinite(hacc).any() else math.nan,
        "clock_ratio": clock_ratio(log),
        "doppler_scale": doppler_scale(log),
        "pauses": logging_pauses(log),
        "losses": receiver_losses(log),
        "err_episodes": nav_err_episodes(log),
        "gaps": record_gaps(log),
        "vib_p50": np.percentile(sd, 50, axis=0).tolist() if len(sd) else None,
        "vib_p90": np.percentile(sd, 90, axis=0).tolist() if len(sd) else None,
        "acc_bins": (bt, sd),
        "ground_alt": float(np.percentile(log.s("gps", "alt")[st >= 3], 2)) if (st >= 3).any() else None,
        "gps_t": t,
        "gps_status": st,
    }


# ---------------------------------------------------------------- one interval

def _sel(t, a, b):
    return (t >= a) & (t <= b)


def _max(x):
    x = x[np.isfinite(x)] if len(x) else x
    return float(np.max(x)) if len(x) else math.nan


def _min(x):
    x = x[np.isfinite(x)] if len(x) else x
    return float(np.min(x)) if len(x) else math.nan


def height_check(log, a, b, w0):
    """Changes since w0 (the window start) of the baro, GPS altitude and the
    integrated GPS Doppler vertical velocity; max disagreements over [a, b]."""
    t, st, alt, vz = (log.s("gps", k) for k in ("t", "status", "alt", "vz"))
    ok = (st >= 3) & np.isfinite(alt) & (t >= w0) & (t <= b)
    if ok.sum() < 2:
        return {}
    tg, ag, vg = t[ok], alt[ok], vz[ok]
    d_gps = ag - ag[0]
    res = {}
    if np.isfinite(vg).all():
        # VZ is positive down (NED); the integral of -VZ is the climb.
        climb = np.r_[0, np.cumsum(-0.5 * (vg[1:] + vg[:-1]) * np.diff(tg))]
        res["dopp_gps"] = climb - d_gps
    if log.has("baro"):
        tb, ab = log.s("baro", "t"), log.s("baro", "alt")
        if tb[0] <= tg[0] and tb[-1] >= tg[0]:
            bi = np.interp(tg, tb, ab)
            res["baro_gps"] = (bi - bi[0]) - d_gps
            if "dopp_gps" in res:
                res["baro_dopp"] = res["baro_gps"] - res["dopp_gps"]
    core = (tg >= a) & (tg <= b)
    out = {}
    for k, v in res.items():
        if core.any():
            i = int(np.argmax(np.abs(v[core])))
            out[k] = float(v[core][i])
    out["vz_max"] = _max(np.abs(vg[core])) if core.any() else math.nan
    return out


def gap_around(log, s, e):
    """The GPS record gap that contains or overlaps [s, e], if any."""
    t = log.s("gps", "t")
    if len(t) < 2:
        return None
    i = int(np.searchsorted(t, s, side="right")) - 1
    j = int(np.searchsorted(t, e, side="left"))
    i, j = max(i, 0), min(j, len(t) - 1)
    if j <= i:
        return None
    # Largest consecutive-record gap between i and j.
    d = np.diff(t[i:j + 1])
    k = i + int(np.argmax(d))
    st, gt, sats = log.s("gps", "status"), log.s("gps", "gtime"), log.s("gps", "sats")
    return {"from": float(t[k]), "to": float(t[k + 1]), "boot": float(t[k + 1] - t[k]),
            "tow": float(gt[k + 1] - gt[k]), "st": (int(st[k]), int(st[k + 1])),
            "sats": (int(sats[k]), int(sats[k + 1])), "bad_between": bool((st[i:j + 1] < 3).any())}


def evidence(log, facts, iv):
    s, e = float(iv["start"]), float(iv["end"])
    a, b = s - CORE_MARGIN_S, e + CORE_MARGIN_S
    w0, w1 = s - CONTEXT_S, e + CONTEXT_S
    ev = {"start": s, "end": e, "dur": e - s, "kind": iv.get("kind"), "driver": iv.get("driver")}
    t, st, sats, hdop, spd = (log.s("gps", k) for k in ("t", "status", "sats", "hdop", "spd"))
    gap = gap_around(log, s, e) if iv.get("kind") == "gps_outage" else None
    if gap:
        a, b = min(a, gap["from"]), max(b, gap["to"])
    c = _sel(t, a, b)
    w = _sel(t, w0, w1)
    ev["n_gps"] = int(c.sum())
    ev["status_min"], ev["sats_min"], ev["hdop_max"] = _min(st[c]), _min(sats[c]), _max(hdop[c])
    ev["status_min_w"], ev["sats_min_w"], ev["hdop_max_w"] = _min(st[w]), _min(sats[w]), _max(hdop[w])
    ta = log.s("acc", "t")
    ca = _sel(ta, a, b)
    ev["hacc_max"], ev["sacc_max"] = _max(log.s("acc", "hacc")[ca]), _max(log.s("acc", "sacc")[ca])
    ev["spd_max"] = _max(spd[c])
    ev["gap"] = gap
    ev["errs"] = [(round(x[0], 2), err_name(x[1], x[2])) for x in log.err if w0 <= x[0] <= w1]
    ev["err_active"] = [nm for (p, q, nm) in facts["err_episodes"] if p <= b and q >= a]
    ev["events"] = [(round(x[0], 2), EV_NAME.get(x[1], str(x[1]))) for x in log.ev if w0 <= x[0] <= w1]
    ev["modes"] = [(round(x[0], 2), x[1]) for x in log.mode if w0 <= x[0] <= w1]
    te = log.s("ekf", "t")
    ce = _sel(te, a, b)
    # |ratio|: 2014 EKF4 stores some as signed int16 percent; all-zero = EKF not running yet.
    ek = {k: _max(np.abs(log.s("ekf", k)[ce])) for k in ("sv", "sp", "sh")} if ce.any() else None
    ev["ekf"] = ek if ek and any(v > 0 for v in ek.values()) else None
    ti = log.s("innov", "t")
    ci = _sel(ti, a, b)
    ev["innov"] = {k: _max(np.abs(log.s("innov", k)[ci])) for k in ("ivn", "ive", "ivd", "ipn", "ipe", "ipd")} \
        if ci.any() else None
    tv = log.s("vibe", "t")
    cv = _sel(tv, a, b)
    ev["vibe"] = [_max(log.s("vibe", k)[cv]) for k in ("x", "y", "z")] if cv.any() else None
    bt, sd = facts["acc_bins"]
    cb = (bt >= a - 0.5) & (bt <= b + 0.5)
    ev["acc_std"] = sd[cb].max(axis=0).tolist() if cb.any() else None
    tt = log.s("att", "t")
    ev["tilt_max"] = _max(log.s("att", "tilt")[_sel(tt, a, b)])
    ev["height"] = height_check(log, a, b, w0)
    # Height over ground: the baro above its low percentile when the log has one
    # (a poor receiver's altitude wanders by 100s of m), else the GPS altitude.
    tb = log.s("baro", "t")
    if len(tb) > 10:
        hb = log.s("baro", "alt")[_sel(tb, a, b)]
        ev["agl"] = float(np.min(hb) - np.percentile(log.s("baro", "alt"), 2)) if len(hb) else None
    else:
        alt = log.s("gps", "alt")[c & (st >= 3)]
        ev["agl"] = float(np.min(alt) - facts["ground_alt"]) if len(alt) and facts["ground_alt"] is not None else None
    ev["verdict"], ev["reason"] = verdict(ev, facts)
    ev["mechanism"] = mechanism(ev, facts)
    return ev


def _fmt(x, p=1):
    return "-" if x is None or (isinstance(x, float) and not math.isfinite(x)) else f"{x:.{p}f}"


def _is_logger_gap(ev):
    g = ev["gap"]
    return bool(g and not g["bad_between"] and min(g["st"]) >= 3)


def verdict(ev, facts):
    if ev["n_gps"] and ev["status_min"] < 3:
        return "TRUE", f"receiver status {int(ev['status_min'])}, sats {_fmt(ev['sats_min'], 0)}"
    if ev["kind"] == "gps_outage":
        # An outage is about the fix alone: only the receiver's status speaks to it.
        g = ev["gap"]
        if _is_logger_gap(ev):
            return "UNCLEAR", (f"logger gap: no GPS record for {g['boot']:.2f} s (boot), receiver time advanced "
                               f"{_fmt(g['tow'], 2)} s, 3D fix and {g['sats'][0]}/{g['sats'][1]} sats on both sides")
        if g is None:
            return "UNCLEAR", "no GPS record after the interval (log ends)"
    if ev["err_active"]:
        return "TRUE", "autopilot error active: " + ", ".join(sorted(set(ev["err_active"])))
    hmed = facts["hacc_median"]
    hj = math.isfinite(ev["hacc_max"]) and ev["hacc_max"] > max(HACC_JUMP_X * hmed if math.isfinite(hmed) else 0,
                                                                 HACC_ABS_M)
    if ev["n_gps"] and (ev["sats_min"] < 6 or ev["hdop_max"] > 3 or hj):
        return "TRUE", (f"receiver degraded: sats {_fmt(ev['sats_min'], 0)}, HDOP {_fmt(ev['hdop_max'], 2)}, "
                        f"hAcc {_fmt(ev['hacc_max'])} m (flight median {_fmt(hmed)})")
    crash = [x for x in ev["errs"] if x[1].startswith("CRASH_CHECK")]
    if (ev["tilt_max"] or 0) > UPSET_DEG or crash:
        return "UNCLEAR", (f"vehicle upset: tilt max {_fmt(ev['tilt_max'], 0)} deg"
                           + (f", {crash[0][1]} at {crash[0][0]} s" if crash else "") + "; not a sensor fault")
    vib = max(ev["acc_std"]) if ev["acc_std"] else 0.0
    vibe = max(ev["vibe"]) if ev["vibe"] else 0.0
    if vib > VIB_STD_MS2 or vibe > VIBE_BAD:
        return "UNCLEAR", f"vibration: accel 1 s std {_fmt(vib)} m/s^2, VIBE {_fmt(vibe)}; the IMU cannot judge"
    k = ev["ekf"]
    if k:
        over = [f"{n.upper()} {v:.2f}" for n, v in k.items() if math.isfinite(v) and v > 1]
        if over:
            return "TRUE", "autopilot EKF test ratio > 1: " + ", ".join(over)
    if ev["n_gps"] and ev["status_min"] >= 3:
        ek = "EKF " + "/".join(f"{n.upper()} {_fmt(v, 2)}" for n, v in k.items()) if k else "no EKF ratios"
        return "FALSE", (f"receiver healthy: 3D, sats >= {_fmt(ev['sats_min'], 0)}, HDOP <= {_fmt(ev['hdop_max'], 2)}"
                         + (f", hAcc <= {_fmt(ev['hacc_max'])} m" if math.isfinite(ev["hacc_max"]) else "")
                         + f"; {ek}; no autopilot error")
    return "UNCLEAR", "no GPS record in the interval"


def mechanism(ev, facts):
    """The likely driver of a non-TRUE interval (issue 14's candidates)."""
    if ev["verdict"] == "TRUE":
        return "real"
    r = ev["reason"]
    if r.startswith("logger gap"):
        return "logger gap"
    if r.startswith("vehicle upset"):
        return "upset/crash"
    if r.startswith("vibration"):
        return "vibration"
    if r.startswith("no GPS record after"):
        return "log end"
    h = ev["height"]
    if ev["driver"] == "baro":
        if "baro_gps" in h and abs(h["baro_gps"]) > BARO_DEPART_M:
            return "baro departs"
        return "baro agrees"
    cr = facts["clock_ratio"]
    if (ev["spd_max"] or 0) > FAST_MS and cr is not None and abs(cr - 1) > CLOCK_BAD:
        return "clock x speed"
    if (ev["spd_max"] or 0) > FAST_MS or (ev["tilt_max"] or 0) > TILT_DEG:
        return "manoeuvre"
    if ev.get("agl") is not None and ev["agl"] < NEAR_GROUND_M:
        return "near ground"
    if any(0 <= ev["start"] - q <= AFTER_OUTAGE_S for (_, q, _) in facts["losses"]):
        return "after outage"
    t, st = facts["gps_t"], facts["gps_status"]
    good = t[st >= 3]
    if len(good) and ev["start"] - good[0] <= START_S:
        return "start of flight"
    return "other"


# ---------------------------------------------------------------- printing

def describe(ev):
    lines = [f"[{ev['start']:.2f}, {ev['end']:.2f}] {ev['dur']:.2f} s  kind {ev['kind']}  driver {ev['driver']}"]
    lines.append(f"  receiver over interval: n {ev['n_gps']}, status min {_fmt(ev['status_min'], 0)}, sats min "
                 f"{_fmt(ev['sats_min'], 0)}, HDOP max {_fmt(ev['hdop_max'], 2)}, hAcc max {_fmt(ev['hacc_max'])} m, "
                 f"sAcc max {_fmt(ev['sacc_max'], 2)} m/s; +-5 s: status min {_fmt(ev['status_min_w'], 0)}, "
                 f"sats min {_fmt(ev['sats_min_w'], 0)}, HDOP max {_fmt(ev['hdop_max_w'], 2)}")
    if ev["gap"]:
        g = ev["gap"]
        lines.append(f"  record gap {g['from']:.2f} -> {g['to']:.2f}: boot {g['boot']:.2f} s, receiver time "
                     f"{_fmt(g['tow'], 2)} s, status {g['st'][0]}/{g['st'][1]}, sats {g['sats'][0]}/{g['sats'][1]}")
    if ev["errs"] or ev["events"] or ev["modes"]:
        lines.append(f"  ERR {ev['errs']}  EV {ev['events']}  MODE {ev['modes']}")
    if ev["ekf"]:
        lines.append("  EKF test ratios max " + " ".join(f"{k.upper()} {_fmt(v, 2)}" for k, v in ev["ekf"].items())
                     + ("  innovations |max| " + " ".join(f"{k.upper()} {_fmt(v, 2)}" for k, v in ev["innov"].items())
                        if ev["innov"] else ""))
    vib = "accel 1 s std " + "/".join(_fmt(x) for x in ev["acc_std"]) if ev["acc_std"] else "no IMU"
    if ev["vibe"]:
        vib += ", VIBE " + "/".join(_fmt(x) for x in ev["vibe"])
    h = ev["height"]
    lines.append(f"  {vib} m/s^2; speed max {_fmt(ev['spd_max'])} m/s, tilt max {_fmt(ev['tilt_max'], 0)} deg, "
                 f"|VZ| max {_fmt(h.get('vz_max'))} m/s, height over ground {_fmt(ev['agl'])} m; since -5 s: baro-GPS {_fmt(h.get('baro_gps'), 2)} m, "
                 f"Doppler-GPS {_fmt(h.get('dopp_gps'), 2)} m, baro-Doppler {_fmt(h.get('baro_dopp'), 2)} m")
    lines.append(f"  => {ev['verdict']}: {ev['reason']}  [mechanism: {ev['mechanism']}]")
    return "\n".join(lines)


def judge(path, cli=DEFAULT_CLI, report=None):
    """(log facts, audit report, [evidence per interval])."""
    log = read_log(path)
    facts = log_facts(log)
    report = report if report is not None else run_audit(cli, path)
    evs = [evidence(log, facts, iv) for iv in report.get("faults", [])]
    return log, facts, report, evs


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("logs", nargs="+")
    ap.add_argument("--cli", default=DEFAULT_CLI, help="navguard.mjs of a built pkg/ (default %(default)s)")
    ap.add_argument("--json", action="store_true", help="one JSON object per log instead of text")
    args = ap.parse_args(argv)
    for p in args.logs:
        log, facts, rep, evs = judge(p, args.cli)
        if args.json:
            f = {k: v for k, v in facts.items() if k not in ("acc_bins", "gps_t", "gps_status")}
            print(json.dumps({"file": p, "facts": f, "intervals": evs}, default=float))
            continue
        cr = facts["clock_ratio"]
        print(f"== {p}: {rep.get('format')}, {facts['gps_records']} GPS records, healthy "
              f"{100 * facts['healthy_share']:.1f}%, boot/GPS clock {_fmt(cr, 4)}, navguard flagged "
              f"{100 * rep.get('flaggedGpsEpochFraction', 0):.2f}% of {rep.get('gpsEpochs')} epochs, "
              f"{len(evs)} intervals")
        for ev in evs:
            print(describe(ev))


if __name__ == "__main__":
    main()
