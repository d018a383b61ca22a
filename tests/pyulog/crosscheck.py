"""Cross-check navguard's ULog reader against pyulog, live.

For every ULog in ../shared/data/px4, compare the data-message count of every
(topic, multi_id) that pyulog reads with the counts navguard's wasm reader
reports (`readLog(...).topicCounts`, key "topic" or "topic/N"), and the
receiver times in its `gps_time` column with vehicle_gps_position's
`time_utc_usec` (every record with a timestamp and a UTC time, in order).
Run by the test command after `pip install pyulog`.
"""
import glob
import json
import os
import subprocess
import sys

from pyulog import ULog

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
DATA = os.path.join(ROOT, "..", "shared", "data", "px4")

JS = """
const ng = require(process.argv[1]);
const fs = require('fs');
const out = {};
for (const f of process.argv.slice(2)) {
  const log = ng.readLog(fs.readFileSync(f));
  const g = log.columns.gps_time ? [...log.columns.gps_time].filter((v) => !Number.isNaN(v)) : [];
  out[f] = { counts: Object.fromEntries(log.topicCounts), gpsTime: g, gpsTopic: Object.fromEntries(log.meta).gps_topic || null };
}
console.log(JSON.stringify(out));
"""

files = sorted(glob.glob(os.path.join(DATA, "*.ulg")))
if len(files) < 6:
    sys.exit(f"expected the 6 PX4 logs in {DATA}, found {len(files)}")
ours = json.loads(subprocess.check_output(["node", "-e", JS, os.path.join(ROOT, "pkg")] + files))
failed = 0
checked = 0
for f in files:
    ulog = ULog(f)
    for d in ulog.data_list:
        key = d.name if d.multi_id == 0 else f"{d.name}/{d.multi_id}"
        want = len(d.data["timestamp"])
        got = ours[f]["counts"].get(key)
        checked += 1
        if got != want:
            failed += 1
            print(f"MISMATCH {os.path.basename(f)} {key}: pyulog {want}, navguard {got}")
    # The receiver's time, where navguard took its GPS from vehicle_gps_position.
    if ours[f]["gpsTopic"] != "vehicle_gps_position":
        continue
    vgp = [d for d in ulog.data_list if d.name == "vehicle_gps_position" and d.multi_id == 0]
    if not vgp or "time_utc_usec" not in vgp[0].data:
        continue
    ts, utc = vgp[0].data["timestamp"], vgp[0].data["time_utc_usec"]
    want = [u / 1e6 for t, u in zip(ts, utc) if t > 0 and u > 0]
    got = ours[f]["gpsTime"]
    checked += 1
    if len(got) != len(want) or any(abs(a - b) > 1e-6 for a, b in zip(got, want)):
        failed += 1
        print(f"MISMATCH {os.path.basename(f)} gps_time: pyulog {len(want)} values, navguard {len(got)}")
print(f"pyulog cross-check: {checked - failed} passed, {failed} failed")
sys.exit(1 if failed else 0)
