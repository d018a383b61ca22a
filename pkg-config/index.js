// Entry point of the npm package: wasm-pack's bindings, with a faster `push`.
// `push(sample)` packs the plain object into one reused Float64Array in JS
// (cheap property reads) and hands it to wasm in a single call, instead of
// 26 property lookups from inside wasm. Same results, same errors.
'use strict';
const core = require('./navguard.js');

const COLS = core.columnNames();
const N = COLS.length;

class Detector extends core.Detector {
  constructor(config) {
    super(config);
    this._row = new Float64Array(N);
  }

  push(sample) {
    if (sample === null || typeof sample !== 'object') {
      throw new Error(`row ${this.rowCount()}: sample must be a plain object`);
    }
    const row = this._row;
    for (let i = 0; i < N; i++) {
      const v = sample[COLS[i]];
      if (v === undefined || v === null) row[i] = NaN;
      else if (typeof v === 'number') row[i] = v;
      else throw new Error(`row ${this.rowCount()}: field '${COLS[i]}': must be a number`);
    }
    return this.pushRow(row);
  }
}

module.exports = { ...core, Detector };
