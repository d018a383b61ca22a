"""Cross-check navguard's ULog reader against pyulog, live.

For every ULog in ../shared/data/px4, compare the data-message count of every
(topic, multi_id) that pyulog reads with the counts navguard's wasm reader
reports (`readLog(...).topicCounts`, key "topic" or "topic/N"). Run by the
test command after `pip install pyulog`.
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
for (const f of process.argv.slice(2)) out[f] = Object.fromEntries(ng.readLog(fs.readFileSync(f)).topicCounts);
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
        got = ours[f].get(key)
        checked += 1
        if got != want:
            failed += 1
            print(f"MISMATCH {os.path.basename(f)} {key}: pyulog {want}, navguard {got}")
print(f"pyulog cross-check: {checked - failed} passed, {failed} failed")
sys.exit(1 if failed else 0)
