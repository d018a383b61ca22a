#!/usr/bin/env python3
"""Write the small hand-made fuzz seeds (synthetic logs, no real data).

Run from anywhere: python3 fuzz/seeds/make_seeds.py. The outputs are
committed; re-run only to change them. Real logs are added to the corpus at
run time by fuzz/run.sh (never committed: their licences differ).
"""
import math
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))


def out(sub, name, data):
    with open(os.path.join(HERE, sub, name), "wb") as f:
        f.write(data)


# ---------------------------------------------------------------- CSV
out("csv", "full.csv", (
    "# navlog written by hand\n# second comment\n"
    "t,lat,lon,alt,vn,ve,vd,fix,sats,eph,epv,ax,ay,az,gx,gy,gz,qw,qx,qy,qz,baro,label\n"
    + "".join(
        f"{0.02*i:.2f},"
        + (f"47.{397742+i},8.{545594+i},{488.0+0.1*i:.1f},0.5,0.2,-0.1,3,12,0.8,1.2," if i % 10 == 0 else ",,,,,,,,,,")
        + f"0.01,-0.02,-9.81,0.001,0.002,-0.001,1,0,0,0,{488.2+0.1*i:.2f},0\n"
        for i in range(40)
    )
).encode())
out("csv", "ned_unknown_cols.csv",
    b"\xef\xbb\xbft , pn, pe, pd, foo ,sats\r\n0,0,0,0,x,9\r\n0.2,0.1,0.2,-0.1,,9\r\n0.4,0.2,0.4,-0.2,y,\r\n0.4,,,,z,8")
out("csv", "errors.csv", b"t,lat,lon\n0,1,2\n0.1,abc,2\n")
out("csv", "gps_only.csv", b"t,lat,lon,alt,fix\n" + b"".join(
    f"{i*0.1:.1f},{47+i*1e-6:.7f},{8+i*1e-6:.7f},500,{3 if i < 20 or i > 30 else 1}\n".encode() for i in range(50)))

# ---------------------------------------------------------------- ULog
def umsg(ty, payload):
    return struct.pack("<HB", len(payload), ord(ty)) + payload


def ufmt(text):
    return umsg("F", text.encode())


def ukv(ty, key, value, prefix=b""):
    k = key.encode()
    return umsg(ty, prefix + bytes([len(k)]) + k + value)


def ulog(version=1, flags=True, cut=None):
    b = b"ULog\x01\x12\x35" + bytes([version]) + struct.pack("<Q", 1000)
    if flags:
        b += umsg("B", bytes(8) + bytes(8) + bytes(24))
    b += ukv("I", "char[3] sys_name", b"PX4")
    b += ukv("I", "char[6] ver_hw", b"SITLv1")
    b += ukv("M", "char[5] multi", b"hello", prefix=b"\x00")
    b += ukv("P", "float MPC_XY_VEL_MAX", struct.pack("<f", 12.0))
    b += ukv("P", "int32_t SYS_AUTOSTART", struct.pack("<i", 4001))
    b += ukv("Q", "int32_t SYS_AUTOSTART", struct.pack("<i", 0), prefix=b"\x01")
    b += ufmt("vehicle_gps_position:uint64_t timestamp;int32_t lat;int32_t lon;int32_t alt;"
              "float eph;float epv;float vel_n_m_s;float vel_e_m_s;float vel_d_m_s;"
              "uint8_t fix_type;uint8_t satellites_used;uint8_t[2] _padding0;")
    b += ufmt("sensor_combined:uint64_t timestamp;float[3] gyro_rad;uint32_t gyro_integral_dt;"
              "int32_t accelerometer_timestamp_relative;float[3] accelerometer_m_s2;"
              "uint32_t accelerometer_integral_dt;")
    b += ufmt("vehicle_attitude:uint64_t timestamp;float[4] q;")
    b += ufmt("vehicle_air_data:uint64_t timestamp;float baro_alt_meter;")
    b += ufmt("esc_report:int32_t rpm;uint8_t[4] _padding0;")
    b += ufmt("esc_status:uint64_t timestamp;esc_report[2] esc;")
    subs = ["vehicle_gps_position", "sensor_combined", "vehicle_attitude", "vehicle_air_data", "esc_status"]
    for i, name in enumerate(subs):
        b += umsg("A", bytes([0]) + struct.pack("<H", i) + name.encode())
    b += umsg("A", bytes([1]) + struct.pack("<H", 5) + b"sensor_combined")
    b += umsg("L", bytes([ord("4")]) + struct.pack("<Q", 1500) + b"[commander] low battery")
    b += umsg("C", bytes([ord("3")]) + struct.pack("<HQ", 7, 1600) + b"tagged error")
    body = b""
    for k in range(40):
        t = 2_000_000 + k * 20_000
        body += umsg("D", struct.pack("<HQ", 1, t) + struct.pack("<3fIi3fI", 0.01, 0.02, -0.01, 4000, 0, 0.1, 0.2, -9.8, 4000))
        body += umsg("D", struct.pack("<HQ", 5, t) + struct.pack("<3fIi3fI", 0.0, 0.0, 0.0, 4000, 2147483647, 0.0, 0.0, -9.8, 4000))
        if k % 2 == 0:
            body += umsg("D", struct.pack("<HQ", 2, t) + struct.pack("<4f", 1.0, 0.0, 0.0, 0.0))
            body += umsg("D", struct.pack("<HQ", 3, t) + struct.pack("<f", 488.0 + k * 0.01))
        if k % 5 == 0:
            fix = 3 if k < 25 else 1
            body += umsg("D", struct.pack("<HQ", 0, t) + struct.pack(
                "<iiifffffBB2x", 473977421 + k, 85455940 + k, 488000, 0.8, 1.2, 0.5, 0.1, -0.1, fix, 12))
            body += umsg("D", struct.pack("<HQ", 4, t) + struct.pack("<i4xi4x", 1000, 1100))
        if k == 20:
            body += umsg("S", bytes([0x2f, 0x73, 0x13, 0x20, 0x25, 0x0c, 0xbb, 0x12]))
            body += umsg("O", struct.pack("<H", 30))
        if k == 30:
            body += umsg("R", struct.pack("<H", 4))
    b += body
    return b[:cut] if cut else b


out("ulog", "synthetic.ulg", ulog())
out("ulog", "synthetic_v0_noflags.ulg", ulog(version=0, flags=False))
out("ulog", "synthetic_cut.ulg", ulog(cut=1500))

# ---------------------------------------------------------------- DataFlash
H = bytes([0xA3, 0x95])


def fmt(ty, length, name, form, cols):
    def pad(s, n):
        return s.encode().ljust(n, b"\0")[:n]
    return H + bytes([128, ty, length]) + pad(name, 4) + pad(form, 16) + pad(cols, 64)


def dataflash(cut=None):
    log = fmt(128, 89, "FMT", "BBnNZ", "Type,Length,Name,Format,Columns")
    log += fmt(130, 3 + 8 + 1 + 1 + 4 + 2 + 1 + 2 + 4 + 4 + 4 + 4 + 4 + 4 + 4 + 1, "GPS",
               "QBBIHBcLLeffffB", "TimeUS,I,Status,GMS,GWk,NSats,HDop,Lat,Lng,Alt,Spd,GCrs,VZ,Yaw,U")
    log += fmt(131, 3 + 8 + 1 + 2 + 2 + 2 + 2 + 4 + 1 + 4 + 2, "GPA", "QBCCCCfBIH",
               "TimeUS,I,VDop,HAcc,VAcc,SAcc,YAcc,VV,SMS,Delta")
    log += fmt(132, 3 + 8 + 1 + 24, "IMU", "QBffffff", "TimeUS,I,GyrX,GyrY,GyrZ,AccX,AccY,AccZ")
    log += fmt(133, 3 + 8 + 8 + 4, "ATT", "QcccccC", "TimeUS,DesRoll,Roll,DesPitch,Pitch,DesYaw,Yaw")
    log += fmt(134, 3 + 8 + 1 + 4, "BARO", "QBi", "TimeUS,I,Alt")
    log += fmt(135, 3 + 8 + 1 + 16 + 16, "FMTU", "QBNN", "TimeUS,FmtType,UnitIds,MultIds")
    log += fmt(136, 3 + 8 + 2 + 1, "ERR", "QBB", "TimeUS,Subsys,ECode")
    log += H + bytes([135]) + struct.pack("<QB", 0, 134) + b"s#m".ljust(16, b"\0") + b"F-B".ljust(16, b"\0")
    for k in range(40):
        t = 1_000_000 + k * 20_000
        if k % 2 == 0:
            log += H + bytes([133]) + struct.pack("<Q5hH", t, 0, 100, 0, -50, 0, 9000)
        log += H + bytes([132]) + struct.pack("<QB6f", t, 0, 0.01, 0.02, 0.03, 0.1, 0.2, -9.8)
        log += H + bytes([132]) + struct.pack("<QB6f", t, 1, 0.01, 0.02, 0.03, 0.1, 0.2, -9.7)
        if k % 4 == 0:
            log += H + bytes([134]) + struct.pack("<QBi", t, 0, 1000 + k)
        if k % 5 == 0:
            status = 3 if k < 25 else 1
            log += H + bytes([130]) + struct.pack("<QBBIHBhiiiffffB", t, 0, status, 123456, 2000, 12, 77,
                                                  -353626277 + k, 1491653034, 58882, 2.0, 90.0, -0.5, 0.0, 1)
            log += H + bytes([131]) + struct.pack("<QB4HfBIH", t, 0, 120, 150, 230, 40, 0.0, 1, 1100, 200)
        if k == 27:
            log += H + bytes([136]) + struct.pack("<QBB", t, 11, 2)
            log += b"\x00garbage\xa3\x95\x07"  # corruption: the reader resyncs
    return log[:cut] if cut else log


def dataflash_old():
    """2014-era: TimeMS, GPS with T (boot ms) and TimeMS (time of week)."""
    log = fmt(128, 89, "FMT", "BBnNZ", "Type,Length,Name,Format,Columns")
    log += fmt(130, 45, "GPS", "BIHBcLLeeEefI", "Status,TimeMS,Week,NSats,HDop,Lat,Lng,RelAlt,Alt,Spd,GCrs,VZ,T")
    log += fmt(131, 31, "IMU", "Iffffff", "TimeMS,GyrX,GyrY,GyrZ,AccX,AccY,AccZ")
    log += fmt(132, 3 + 4 + 12, "ATT", "IccccCC", "TimeMS,DesRoll,Roll,DesPitch,Pitch,DesYaw,Yaw")
    for k in range(30):
        t = 97_000 + k * 20
        log += H + bytes([131]) + struct.pack("<I6f", t, 0.0, 0.0, 0.0, 0.0, 0.0, -9.8)
        log += H + bytes([132]) + struct.pack("<I4h2H", t, 0, 10, 0, -10, 0, 18000)
        if k % 5 == 0:
            log += H + bytes([130]) + struct.pack("<BIHBhiiiiIifI", 3, 300_000_000 + t, 1800, 9, 150,
                                                  -353626277, 1491653034, 1000, 58000, 200, 9000, 0.1, t)
    return log


out("dataflash", "synthetic_timeus.bin", dataflash())
out("dataflash", "synthetic_timems.bin", dataflash_old())
out("dataflash", "synthetic_cut.bin", dataflash(cut=1700))

# ---------------------------------------------------------------- push
# The push target decodes bytes with `arbitrary`; any bytes are a valid seed.
out("push", "zeros", bytes(256))
out("push", "ramp", bytes(range(256)) * 4)
out("push", "ones", b"\x01" * 512)
