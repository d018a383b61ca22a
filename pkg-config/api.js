// The package's API, the same on every target (Node ESM and CJS, bundlers,
// a plain <script type="module">): the wasm-bindgen bindings of the three
// modules behind thin guards. Only the entry files differ (node.js,
// navguard.js for browsers): they say where the .wasm bytes come from
// (loader.js).
//
// Three wasm modules (see src/wasm/mod.rs): the core (the detector with its
// snapshots, the log readers: what `new Detector()` plus `readLog` need)
// loads on `init()` or, in Node, on first use. The audit module (auditBytes,
// Auditor, StreamAuditor, metrics, with its own detector and readers) and
// the lab (simulators, compare, training, tightly coupled) load only when
// one of their APIs is first used: synchronously in Node, after
// `await loadAudit()` / `await loadLab()` in browsers (where compiling a
// large module synchronously is not allowed everywhere).
//
// The Rust side reads every user value through catching calls and checks it
// before touching state (src/wasm/interop.rs). Two hazards live in the
// generated glue itself, before any Rust runs, and are closed here:
// - A method called on a freed object (or after a double `free()`) makes the
//   glue's shim throw from inside wasm; with an object argument that leaks a
//   slot of wasm-bindgen's reference table each time, and after ~1,000 calls
//   the module traps. Every method checks for a freed object first.
// - A getter on a sample or batch that calls back into the same object
//   (re-entry) would interleave its rows with the outer call's. Every method
//   refuses to start while another one is running on the same object.
//
// `push(sample)` packs the plain object into the detector's row buffer in
// wasm memory in JS (cheap property reads) and runs it with one call with no
// arguments, instead of 28 property lookups from inside wasm. Same results,
// same errors.
import * as core from './navguard_core.js';
import * as audit from './navguard_audit.js';
import * as lab from './navguard_lab.js';
import { loader } from './loader.js';

// ---- module loading ----------------------------------------------------

let coreReady = false;
let auditReady = false;
let labReady = false;
let corePromise = null;
let auditPromise = null;
let labPromise = null;

// Per-module state read once the core is instantiated.
let COLS = null;
let N = 0;
let INDEX = null;
let memory = null;

function coreLoaded() {
  COLS = core.columnNames();
  N = COLS.length;
  INDEX = Object.create(null);
  COLS.forEach((c, i) => { INDEX[c] = i; });
  memory = core.__memory();
  coreReady = true;
}

// Make sure the core module is instantiated: synchronously where the
// entry can (Node), else it must have been loaded by `init()`.
function needCore() {
  if (coreReady) return;
  if (!loader.coreSync) throw new Error('navguard: the wasm module is not loaded yet: `await init()` first');
  core.initSync({ module: loader.coreSync() });
  coreLoaded();
}

function needAudit() {
  if (auditReady) return;
  if (!loader.auditSync) {
    throw new Error('navguard: the audit module (auditBytes, Auditor, StreamAuditor, metrics) is not loaded yet: `await loadAudit()` first');
  }
  audit.initSync({ module: loader.auditSync() });
  auditReady = true;
}

function needLab() {
  if (labReady) return;
  if (!loader.labSync) {
    throw new Error('navguard: the lab module (simulators, compare, training, tightly coupled) is not loaded yet: `await loadLab()` first');
  }
  lab.initSync({ module: loader.labSync() });
  labReady = true;
}

/** Load the core wasm module. Needed once in browsers before any other call;
 * optional in Node (the module loads on first use). */
export function init() {
  if (coreReady) return Promise.resolve();
  corePromise ??= (async () => {
    const bytes = await loader.core();
    if (!coreReady) {
      await core.default({ module_or_path: bytes });
      coreLoaded();
    }
  })();
  corePromise.catch(() => { corePromise = null; });
  return corePromise;
}

/** Load the audit module (auditBytes, Auditor, StreamAuditor, metrics).
 * Needed once in browsers before those; optional in Node. */
export function loadAudit() {
  if (auditReady) return Promise.resolve();
  auditPromise ??= (async () => {
    const bytes = await loader.audit();
    if (!auditReady) {
      await audit.default({ module_or_path: bytes });
      auditReady = true;
    }
  })();
  auditPromise.catch(() => { auditPromise = null; });
  return auditPromise;
}

/** Load the lab module (simulators, comparison, training, tightly coupled
 * detector). Needed once in browsers before a lab API; optional in Node. */
export function loadLab() {
  if (labReady) return Promise.resolve();
  labPromise ??= (async () => {
    const bytes = await loader.lab();
    if (!labReady) {
      await lab.default({ module_or_path: bytes });
      labReady = true;
    }
  })();
  labPromise.catch(() => { labPromise = null; });
  return labPromise;
}

/** Which wasm modules are instantiated (for size checks). */
export function loadedModules() {
  return { core: coreReady, audit: auditReady, lab: labReady };
}

export default init;

// ---- guards ------------------------------------------------------------

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

// Guard every method of `Class` (a subclass of the raw class `Raw`) but
// those in `own` (which guard themselves); make `free()` idempotent.
function guardClass(Class, Raw, name, own = []) {
  const keys = new Set([...Object.getOwnPropertyNames(Raw.prototype), ...Object.getOwnPropertyNames(Class.prototype)]);
  for (const key of keys) {
    if (key === 'constructor' || key === 'free' || own.includes(key) || key.startsWith('__')) continue;
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

// A module function that first makes sure its module is loaded.
const coreFn = (f) => function (...args) { needCore(); return f(...args); };
const auditFn = (f) => function (...args) { needAudit(); return f(...args); };
const labFn = (f) => function (...args) { needLab(); return f(...args); };

// ---- the core module ---------------------------------------------------

// The raw methods, called directly: an own property of the user's cannot
// stand in for them.
const rawPushIo = core.Detector.prototype.__pushIo;
const rawIoOffset = core.Detector.prototype.__ioOffset;
const rawRowCount = core.Detector.prototype.rowCount;

const initDetector = (d) => {
  d._row = new Float64Array(N);
  d._io = null;
};

export class Detector extends core.Detector {
  constructor(config) {
    needCore();
    super(config);
    initDetector(this);
  }

  static restore(snapshot) {
    needCore();
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
  // Walk the sample's own keys: rows are sparse (an IMU row has ~10 of 28).
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
  if (io === null || io.length === 0) io = det._io = new Float64Array(memory.buffer, rawIoOffset.call(det), N + 7);
  io.set(row);
  rawPushIo.call(det);
  if (io.length === 0) io = det._io = new Float64Array(memory.buffer, rawIoOffset.call(det), N + 7);
  return { t: io[N], status: io[N + 1], f: io[N + 2], r: io[N + 3], c: io[N + 4], kind: io[N + 5], gpsEpoch: io[N + 6] === 1 };
}
guardClass(Detector, core.Detector, 'Detector', ['push']);

export const readLog = coreFn(core.readLog);
export const snapshotInfo = coreFn(core.snapshotInfo);
export const columnNames = coreFn(core.columnNames);
export const version = coreFn(core.version);
export const scenarioNames = coreFn(core.scenarioNames);

/** Bytes of wasm linear memory: the core's, plus the audit module's once
 * it is loaded (what an audit grows). */
export function wasmMemoryBytes() {
  needCore();
  return core.wasmMemoryBytes() + (auditReady ? audit.__wasmMemoryBytes() : 0);
}

// ---- the audit module --------------------------------------------------

export class Auditor extends audit.Auditor {
  constructor(bytes, config) {
    needAudit();
    super(bytes, config);
  }
}
guardClass(Auditor, audit.Auditor, 'Auditor');

export class StreamAuditor extends audit.StreamAuditor {
  constructor(config, keepOutputs) {
    needAudit();
    super(config, keepOutputs);
  }
}
guardClass(StreamAuditor, audit.StreamAuditor, 'StreamAuditor');

export const auditBytes = auditFn(audit.auditBytes);
export const metrics = auditFn(audit.metrics);

// ---- the lab module ----------------------------------------------------

export class TightDetector extends lab.TightDetector {
  constructor(config) {
    needLab();
    super(config);
  }

  static withGanModel(config, model) {
    needLab();
    return adopt(TightDetector, lab.TightDetector.withGanModel(config, model));
  }
}
guardClass(TightDetector, lab.TightDetector, 'TightDetector');

export class CompareRun extends lab.CompareRun {
  constructor(options) {
    needLab();
    super(options);
  }
}
guardClass(CompareRun, lab.CompareRun, 'CompareRun');

export const simulate = labFn(lab.simulate);
export const simulateScenario = labFn(lab.simulateScenario);
export const trainFromCsv = labFn(lab.trainFromCsv);
export const tightSimulate = labFn(lab.tightSimulate);
export const tightGanTrain = labFn(lab.tightGanTrain);
