// Entry point of the npm package: wasm-pack's bindings, with a faster `push`.
// `push(sample)` packs the plain object into one reused Float64Array in JS
// (cheap property reads) and hands it to wasm in a single call, instead of
// 26 property lookups from inside wasm. Same results, same errors.
'use strict';
const core = require('./navguard.js');

const COLS = core.columnNames();
const N = COLS.length;
const INDEX = Object.create(null);
COLS.forEach((c, i) => { INDEX[c] = i; });

class Detector extends core.Detector {
  constructor(config) {
    super(config);
    this._row = new Float64Array(N);
    this._out = new Float64Array(7);
  }

  // The wasm static returns a plain core.Detector; give it this class's
  // fast `push` and buffers.
  static restore(snapshot) {
    const d = core.Detector.restore(snapshot);
    Object.setPrototypeOf(d, Detector.prototype);
    d._row = new Float64Array(N);
    d._out = new Float64Array(7);
    return d;
  }

  push(sample) {
    if (sample === null || typeof sample !== 'object') {
      throw new Error(`row ${this.rowCount()}: sample must be a plain object`);
    }
    const row = this._row;
    row.fill(NaN);
    // Walk the sample's own keys: rows are sparse (an IMU row has ~10 of 26).
    for (const k in sample) {
      const i = INDEX[k];
      if (i === undefined) continue;
      const v = sample[k];
      if (typeof v === 'number') row[i] = v;
      else if (v !== undefined && v !== null) throw new Error(`row ${this.rowCount()}: field '${k}': must be a number`);
    }
    const o = this._out;
    this.pushRowInto(row, o);
    return { t: o[0], status: o[1], f: o[2], r: o[3], c: o[4], kind: o[5], gpsEpoch: o[6] === 1 };
  }
}

module.exports = { ...core, Detector };
