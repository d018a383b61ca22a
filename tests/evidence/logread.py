"""Independent log readers for the evidence tool (not navguard's readers).

DataFlash (.bin/.BIN) through pymavlink, PX4 ULog through pyulog, navlog CSV
through the csv module. Every reader returns a `Log`: named numpy series on
the log's own boot clock (s), the clock navguard's audit reports use
(contract section 3: ULog `timestamp`/1e6, DataFlash `TimeUS`/1e6, or
`TimeMS`/1e3 in 2014-era logs, where the GPS message's boot time is `T`).

Series (any may be absent; absent = an empty array):
  gps      t, status (fix type: 0 no GPS, 1 no fix, 2 2D, 3 3D, 4+ DGPS/RTK),
           sats, hdop, alt (m AMSL), vz (m/s, positive down), spd (m/s),
           gtime (receiver GPS time, s since the GPS epoch; NaN if unknown),
           DataFlash only: lat, lon (deg), crs (course over ground, deg)
  acc      t, hacc, vacc, sacc (m, m, m/s): DataFlash GPA or UBX3, PX4 eph/epv/s_variance
  ekf      t, sv, sp, sh (test ratios) and ivn ive ivd ipn ipe ipd (innovations)
  vibe     t, x, y, z (m/s^2; ArduPilot VIBE or PX4 estimator_status.vibe)
  imu      t, ax, ay, az (m/s^2)
  baro     t, alt (m)
  att      t, tilt (deg, from roll and pitch)
  err      list of (t, subsys, ecode)   (ArduPilot ERR)
  ev       list of (t, id)              (ArduPilot EV)
  mode     list of (t, name)            (ArduPilot MODE, PX4 nav_state)
  fs       t, failsafe (PX4 vehicle_status.failsafe)
  times    every time-stamped message time (for logging pauses)
"""
import csv
import math
import os

import numpy as np

GPS_EPOCH_WEEK_S = 604800.0


def _arr(v):
    return np.asarray(v, dtype=float)


class Log:
    """A read log: `series[name][field]` numpy arrays plus event lists."""

    def __init__(self, path, fmt):
        self.path = path
        self.fmt = fmt
        self.series = {}
        self.err = []
        self.ev = []
        self.mode = []
        self.meta = {}
        self.times = np.zeros(0)

    def s(self, name, field):
        """Field of a series, or an empty array when the log lacks it."""
        return self.series.get(name, {}).get(field, np.zeros(0))

    def has(self, name):
        return name in self.series and len(self.series[name]["t"]) > 0

    def put(self, name, cols):
        cols = {k: _arr(v) for k, v in cols.items()}
        order = np.argsort(cols["t"], kind="stable")
        self.series[name] = {k: v[order] for k, v in cols.items()}


def detect_format(path):
    with open(path, "rb") as f:
        head = f.read(8)
    if head[:4] == b"ULog":
        return "ulog"
    if head[:2] == b"\xa3\x95":
        return "dataflash"
    return "csv"


def read_log(path):
    fmt = detect_format(path)
    return {"ulog": read_ulog, "dataflash": read_dataflash, "csv": read_csv}[fmt](path)


# ---------------------------------------------------------------- DataFlash

def _boot_time(msg, mtype, d):
    """Boot clock (s) of a DataFlash message, or None when it carries none.

    Old (TimeMS-era) GPS messages: TimeMS is GPS time of week, T is boot ms."""
    if "TimeUS" in d:
        return d["TimeUS"] / 1e6
    if mtype == "GPS":
        return d["T"] / 1e3 if "T" in d else None
    if "TimeMS" in d:
        return d["TimeMS"] / 1e3
    return None


_DF_WANTED = {"GPS", "GPA", "UBX3", "ERR", "EV", "MODE", "IMU", "BARO", "ATT", "VIBE",
              "EKF3", "EKF4", "NKF3", "NKF4", "XKF3", "XKF4"}


def read_dataflash(path):
    from pymavlink import DFReader

    log = Log(path, "dataflash")
    r = DFReader.DFReader_binary(path, zero_time_base=True)
    g = {k: [] for k in ("t", "status", "sats", "hdop", "alt", "vz", "spd", "gtime", "lat", "lon", "crs")}
    acc = {k: [] for k in ("t", "hacc", "vacc", "sacc")}
    ekf3, ekf4 = {}, {}
    imu = {k: [] for k in ("t", "ax", "ay", "az")}
    baro = {"t": [], "alt": []}
    att = {"t": [], "tilt": []}
    vibe = {k: [] for k in ("t", "x", "y", "z")}
    times = []
    last_t = None
    while True:
        try:
            m = r.recv_msg()
        except Exception as e:  # a damaged tail: keep what was read
            log.meta["read_error"] = str(e)
            break
        if m is None:
            break
        mtype = m.get_type()
        if mtype not in _DF_WANTED and mtype in ("FMT", "FMTU", "PARM", "MSG", "MULT", "UNIT"):
            continue
        names = m.get_fieldnames()
        d = {k: getattr(m, k, None) for k in names} if mtype in _DF_WANTED else \
            {k: getattr(m, k) for k in ("TimeUS", "TimeMS") if k in names}
        if mtype == "GPS" and "T" in names:
            d["T"] = m.T
        t = _boot_time(m, mtype, d)
        if t is not None and t > 0:
            last_t = t
            times.append(t)
        if mtype not in _DF_WANTED:
            continue
        tt = t if t is not None else last_t
        if tt is None:
            tt = 0.0
        if mtype == "GPS":
            if d.get("I", 0) not in (0, None):
                continue
            tow_ms = d.get("GMS", d.get("TimeMS") if "T" in d else None)
            week = d.get("GWk", d.get("Week"))
            gt = week * GPS_EPOCH_WEEK_S + tow_ms / 1e3 if (tow_ms and week) else math.nan
            g["t"].append(tt)
            g["status"].append(d["Status"])
            g["sats"].append(d["NSats"])
            g["hdop"].append(d["HDop"])
            g["alt"].append(d["Alt"])
            g["vz"].append(d.get("VZ", math.nan))
            g["spd"].append(d.get("Spd", math.nan))
            g["gtime"].append(gt)
            g["lat"].append(d["Lat"])
            g["lon"].append(d["Lng"])
            g["crs"].append(d.get("GCrs", math.nan))
        elif mtype == "GPA" and d.get("I", 0) in (0, None):
            acc["t"].append(tt)
            acc["hacc"].append(d["HAcc"])
            acc["vacc"].append(d["VAcc"])
            acc["sacc"].append(d["SAcc"])
        elif mtype == "UBX3" and d.get("Instance", 0) == 0:
            acc["t"].append(tt)
            acc["hacc"].append(d["hAcc"])
            acc["vacc"].append(d["vAcc"])
            acc["sacc"].append(d["sAcc"])
        elif mtype in ("EKF3", "NKF3", "XKF3"):
            if mtype == "XKF3" and d.get("C", 0) != 0:
                continue
            row = {"t": tt}
            for k in ("IVN", "IVE", "IVD", "IPN", "IPE", "IPD"):
                row[k.lower()] = d.get(k, math.nan)
            ekf3.setdefault(mtype, []).append(row)
        elif mtype in ("EKF4", "NKF4", "XKF4"):
            if mtype == "XKF4" and d.get("C", 0) != 0:
                continue
            ekf4.setdefault(mtype, []).append(
                {"t": tt, "sv": d.get("SV", math.nan), "sp": d.get("SP", math.nan), "sh": d.get("SH", math.nan)})
        elif mtype == "IMU" and d.get("I", 0) in (0, None):
            imu["t"].append(tt)
            imu["ax"].append(d["AccX"])
            imu["ay"].append(d["AccY"])
            imu["az"].append(d["AccZ"])
        elif mtype == "BARO" and d.get("I", 0) in (0, None):
            baro["t"].append(tt)
            baro["alt"].append(d["Alt"])
        elif mtype == "ATT":
            r_, p_ = math.radians(d["Roll"]), math.radians(d["Pitch"])
            att["t"].append(tt)
            att["tilt"].append(math.degrees(math.acos(max(-1.0, min(1.0, math.cos(r_) * math.cos(p_))))))
        elif mtype == "VIBE" and d.get("IMU", 0) in (0, None):
            vibe["t"].append(tt)
            vibe["x"].append(d["VibeX"])
            vibe["y"].append(d["VibeY"])
            vibe["z"].append(d["VibeZ"])
        elif mtype == "ERR":
            log.err.append((tt, int(d["Subsys"]), int(d["ECode"])))
        elif mtype == "EV":
            log.ev.append((tt, int(d["Id"])))
        elif mtype == "MODE":
            log.mode.append((tt, str(d.get("Mode"))))
    log.put("gps", g)
    log.put("acc", acc)
    log.put("imu", imu)
    log.put("baro", baro)
    log.put("att", att)
    log.put("vibe", vibe)
    # One EKF instance: the first core of the newest family present.
    for k3, k4 in (("XKF3", "XKF4"), ("NKF3", "NKF4"), ("EKF3", "EKF4")):
        if k3 in ekf3 or k4 in ekf4:
            rows3, rows4 = ekf3.get(k3, []), ekf4.get(k4, [])
            e = {"t": [x["t"] for x in rows4], "sv": [x["sv"] for x in rows4],
                 "sp": [x["sp"] for x in rows4], "sh": [x["sh"] for x in rows4]}
            log.put("ekf", e)
            log.put("innov", {k: [x[k] for x in rows3] for k in ("t", "ivn", "ive", "ivd", "ipn", "ipe", "ipd")})
            log.meta["ekf_msgs"] = f"{k3}/{k4}"
            break
    log.times = np.sort(_arr(times))
    return log


# ---------------------------------------------------------------- ULog

def _topic(u, name, multi=0):
    for d in u.data_list:
        if d.name == name and d.multi_id == multi:
            return d.data
    return None


def read_ulog(path):
    from pyulog import ULog

    log = Log(path, "ulog")
    u = ULog(path)
    times = []
    for d in u.data_list:
        times.append(d.data["timestamp"])
    if times:
        t_all = np.concatenate(times).astype(float) / 1e6
        log.times = np.sort(t_all[t_all > 0])
    gname = "vehicle_gps_position" if _topic(u, "vehicle_gps_position") is not None else "sensor_gps"
    gp = _topic(u, gname)
    log.meta["gps_topic"] = gname if gp is not None else None
    if gp is not None:
        ts = gp["timestamp"].astype(float)
        keep = ts > 0
        alt = gp["altitude_msl_m"] if "altitude_msl_m" in gp else gp["alt"] / 1e3
        utc = gp["time_utc_usec"].astype(float) / 1e6 if "time_utc_usec" in gp else np.full(len(ts), np.nan)
        utc = np.where(utc > 0, utc, np.nan)
        log.put("gps", {"t": (ts / 1e6)[keep], "status": gp["fix_type"][keep], "sats": gp["satellites_used"][keep],
                        "hdop": gp["hdop"][keep], "alt": alt[keep], "vz": gp["vel_d_m_s"][keep],
                        "spd": gp["vel_m_s"][keep], "gtime": utc[keep]})
        log.put("acc", {"t": (ts / 1e6)[keep], "hacc": gp["eph"][keep], "vacc": gp["epv"][keep],
                        "sacc": gp["s_variance_m_s"][keep]})
    es = _topic(u, "estimator_status")
    if es is not None and "vel_test_ratio" in es:
        log.put("ekf", {"t": es["timestamp"] / 1e6, "sv": es["vel_test_ratio"], "sp": es["pos_test_ratio"],
                        "sh": es["hgt_test_ratio"]})
    if es is not None and "vibe[0]" in es:
        log.put("vibe", {"t": es["timestamp"] / 1e6, "x": es["vibe[0]"], "y": es["vibe[1]"], "z": es["vibe[2]"]})
    sc = _topic(u, "sensor_combined")
    if sc is not None:
        log.put("imu", {"t": sc["timestamp"] / 1e6, "ax": sc["accelerometer_m_s2[0]"],
                        "ay": sc["accelerometer_m_s2[1]"], "az": sc["accelerometer_m_s2[2]"]})
    for bname in ("vehicle_air_data", "sensor_baro"):
        b = _topic(u, bname)
        if b is not None and "baro_alt_meter" in b:
            log.put("baro", {"t": b["timestamp"] / 1e6, "alt": b["baro_alt_meter"]})
            break
    va = _topic(u, "vehicle_attitude")
    if va is not None and "q[0]" in va:
        w, x, y, z = (va[f"q[{i}]"] for i in range(4))
        # Tilt = angle between body z and NED down: cos = 1 - 2(x^2 + y^2).
        c = np.clip(1 - 2 * (x * x + y * y), -1, 1)
        log.put("att", {"t": va["timestamp"] / 1e6, "tilt": np.degrees(np.arccos(c))})
    vs = _topic(u, "vehicle_status")
    if vs is not None:
        log.put("fs", {"t": vs["timestamp"] / 1e6, "failsafe": vs["failsafe"]})
        prev = None
        for t, n in zip(vs["timestamp"] / 1e6, vs["nav_state"]):
            if n != prev:
                log.mode.append((float(t), f"nav_state {int(n)}"))
                prev = n
    return log


# ---------------------------------------------------------------- CSV

def read_csv(path):
    log = Log(path, "csv")
    with open(path, newline="") as f:
        lines = (ln for ln in f if not ln.startswith("#"))
        rows = list(csv.DictReader(lines))

    def col(r, k):
        v = r.get(k, "")
        return float(v) if v not in ("", None) else math.nan

    g = {k: [] for k in ("t", "status", "sats", "hdop", "alt", "vz", "spd", "gtime")}
    acc = {k: [] for k in ("t", "hacc", "vacc", "sacc")}
    imu = {k: [] for k in ("t", "ax", "ay", "az")}
    baro = {"t": [], "alt": []}
    times = []
    for r in rows:
        t = col(r, "t")
        times.append(t)
        has_pos = all(not math.isnan(col(r, k)) for k in ("lat", "lon", "alt")) or \
            all(not math.isnan(col(r, k)) for k in ("pn", "pe", "pd"))
        fix = col(r, "fix")
        if has_pos or not math.isnan(fix):
            alt = col(r, "alt") if not math.isnan(col(r, "alt")) else -col(r, "pd")
            g["t"].append(t)
            g["status"].append(fix if not math.isnan(fix) else (3 if has_pos else 0))
            g["sats"].append(col(r, "sats"))
            g["hdop"].append(math.nan)
            g["alt"].append(alt)
            g["vz"].append(col(r, "vd"))
            g["spd"].append(math.hypot(col(r, "vn"), col(r, "ve")))
            g["gtime"].append(math.nan)
            acc["t"].append(t)
            acc["hacc"].append(col(r, "eph"))
            acc["vacc"].append(col(r, "epv"))
            acc["sacc"].append(math.nan)
        if not math.isnan(col(r, "ax")):
            imu["t"].append(t)
            for k in ("ax", "ay", "az"):
                imu[k].append(col(r, k))
        if not math.isnan(col(r, "baro")):
            baro["t"].append(t)
            baro["alt"].append(col(r, "baro"))
    log.put("gps", g)
    log.put("acc", acc)
    log.put("imu", imu)
    log.put("baro", baro)
    log.times = np.sort(_arr(times))
    return log


if __name__ == "__main__":
    import sys

    for p in sys.argv[1:]:
        lg = read_log(p)
        print(os.path.basename(p), lg.fmt, {k: len(v["t"]) for k, v in lg.series.items()},
              "err", len(lg.err), "ev", len(lg.ev), "mode", len(lg.mode), lg.meta)
