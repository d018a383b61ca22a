// Entry point of the npm package: wasm-pack's bindings behind a thin guard.
//
// The Rust side reads every user value through catching calls and checks it
// before touching state (src/wasm/js_in.rs). Two hazards live in the
// generated glue itself, before any Rust runs, and are closed here:
// - A method called on a freed object (or after a double `free()`) makes the
//   glue's shim throw from inside wasm; with an object argument that leaks a
//   slot of wasm-bindgen's reference table each time, and after ~1,000 calls
//   the module traps. Every method checks for a freed object first.
// - A getter on a sample or batch that calls back into the same object
//   (re-entry) would interleave its rows with the outer call's. Every method
//   refuses to start while another one is running on the same object.
//
// `push(sample)` packs the plain object into one reused Float64Array in JS
// (cheap property reads) and hands it to wasm in a single call, instead of
// 26 property lookups from inside wasm. Same results, same errors.
'use strict';
const core = require('./navguard.js');

const COLS = core.columnNames();
const N = COLS.length;
const INDEX = Object.create(null);
COLS.forEach((c, i) => { INDEX[c] = i; });

// A thrown value as text, whatever it is.
function describe(e) {
  try {
    return e instanceof Error ? String(e.message) : String(e);
  } catch {
    return 'an unprintable value';
  }
}

// Which method is running on an object (re-entry guard).
const BUSY = Symbol('navguard.running');

function enter(obj, Raw, name, key) {
  if (!(obj instanceof Raw) || !obj.__wbg_ptr) {
    throw new Error(`${name}.${key}: this ${name} was freed (free() was called), or 'this' is not a ${name}`);
  }
  if (obj[BUSY]) {
    throw new Error(`${name}.${key}: called while ${name}.${obj[BUSY]} is running on the same object (from a getter or callback of its argument); this call did nothing`);
  }
  obj[BUSY] = key;
}

// `Class.prototype[key]` (a method of the raw class `Raw`) behind the freed
// and re-entry checks.
function guardMethod(Class, Raw, name, key) {
  const f = Class.prototype[key];
  Object.defineProperty(Class.prototype, key, {
    configurable: true,
    writable: true,
    value: function (...args) {
      enter(this, Raw, name, key);
      try {
        return f.apply(this, args);
      } finally {
        this[BUSY] = undefined;
      }
    },
  });
}

// Guard every method of `Class` (a subclass of the raw class `Raw`); make
// `free()` idempotent.
function guardClass(Class, Raw, name) {
  const keys = new Set([...Object.getOwnPropertyNames(Raw.prototype), ...Object.getOwnPropertyNames(Class.prototype)]);
  for (const key of keys) {
    if (key === 'constructor' || key === 'free' || key === 'push' || key.startsWith('__')) continue;
    if (typeof Class.prototype[key] !== 'function') continue;
    guardMethod(Class, Raw, name, key);
  }
  const free = Raw.prototype.free;
  Class.prototype.free = function () {
    if (!(this instanceof Raw) || !this.__wbg_ptr) return;
    if (this[BUSY]) throw new Error(`${name}.free: called while ${name}.${this[BUSY]} is running on the same object`);
    free.call(this);
    // A Detector's view on its freed row buffer must not outlive it.
    if (this._io) this._io = null;
  };
  if (Symbol.dispose) Class.prototype[Symbol.dispose] = Class.prototype.free;
  return Class;
}

// A raw instance made by a static method, given this class's prototype.
function adopt(Class, obj, init) {
  Object.setPrototypeOf(obj, Class.prototype);
  if (init) init(obj);
  return obj;
}

const memory = core.__memory();
const rawPushIo = core.Detector.prototype.__pushIo;
const rawRowCount = core.Detector.prototype.rowCount;
const initDetector = (d) => {
  d._row = new Float64Array(N);
  d._io = null;
};

class Detector extends core.Detector {
  constructor(config) {
    super(config);
    initDetector(this);
  }

  static restore(snapshot) {
    return adopt(Detector, core.Detector.restore(snapshot), initDetector);
  }

  push(sample) {
    enter(this, core.Detector, 'Detector', 'push');
    try {
      return pushSample(this, sample);
    } finally {
      this[BUSY] = undefined;
    }
  }
}

function pushSample(det, sample) {
  if (sample === null || typeof sample !== 'object') {
    throw new Error(`row ${rawRowCount.call(det)}: sample must be a plain object`);
  }
  const row = det._row;
  row.fill(NaN);
  // Walk the sample's own keys: rows are sparse (an IMU row has ~10 of 26).
  // A getter here that calls back into this detector is refused (BUSY); a
  // getter or Proxy trap that throws anything becomes an Error naming the row.
  let bad = null;
  let k = null;
  try {
    for (k in sample) {
      const i = INDEX[k];
      if (i === undefined) continue;
      const v = sample[k];
      if (typeof v === 'number') row[i] = v;
      else if (v !== undefined && v !== null) {
        bad = k;
        break;
      }
    }
  } catch (e) {
    const what = k === null ? 'listing its fields' : `field '${k}'`;
    throw new Error(`row ${rawRowCount.call(det)}: sample: ${what}: reading it threw: ${describe(e)}`, { cause: e });
  }
  if (bad !== null) throw new Error(`row ${rawRowCount.call(det)}: field '${bad}': must be a number`);
  // The detector's row buffer in wasm memory, filled only now that no
  // getter can run any more. A view made before memory grew is detached
  // (length 0): make a new one, before the push and after it.
  let io = det._io;
  if (io === null || io.length === 0) io = det._io = new Float64Array(memory.buffer, det.__ioOffset(), N + 7);
  io.set(row);
  rawPushIo.call(det);
  if (io.length === 0) io = det._io = new Float64Array(memory.buffer, det.__ioOffset(), N + 7);
  return { t: io[N], status: io[N + 1], f: io[N + 2], r: io[N + 3], c: io[N + 4], kind: io[N + 5], gpsEpoch: io[N + 6] === 1 };
}
guardClass(Detector, core.Detector, 'Detector');

class TightDetector extends core.TightDetector {
  static withGanModel(config, model) {
    return adopt(TightDetector, core.TightDetector.withGanModel(config, model));
  }
}
guardClass(TightDetector, core.TightDetector, 'TightDetector');

class Auditor extends core.Auditor {}
guardClass(Auditor, core.Auditor, 'Auditor');
class StreamAuditor extends core.StreamAuditor {}
guardClass(StreamAuditor, core.StreamAuditor, 'StreamAuditor');
class CompareRun extends core.CompareRun {}
guardClass(CompareRun, core.CompareRun, 'CompareRun');

// The raw classes are replaced by the guarded ones; `__` helpers are not API.
const api = Object.fromEntries(Object.entries(core).filter(([k]) => !k.startsWith('__')));
module.exports = { ...api, Detector, TightDetector, Auditor, StreamAuditor, CompareRun };
