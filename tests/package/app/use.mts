// Type-checked by tests/package/package.test.mjs with `tsc --strict`, no
// @types/node and no DOM lib: the public d.ts must stand on its own.
import init, { Detector, auditBytes, readLog, snapshotInfo, loadLab, type PushResult, type ColumnsResult, type AuditResult, type LogColumns } from 'navguard';

await init();
const det = new Detector();
const tuned = new Detector({ method: 'chi2', tc: 50 });
const one: PushResult = det.push({ t: 0, ax: 0, ay: 0, az: -9.81 });
const cols: ColumnsResult = det.pushColumns({ t: new Float64Array([1, 2]), baro: new Float64Array([10, 10.1]) });
const bytes = new Uint8Array(0);
const log: LogColumns = readLog(bytes);
const audit: AuditResult = auditBytes(bytes);
const audit2: AuditResult = auditBytes(bytes, { window: 20 });
const snap: Uint8Array = det.snapshot();
const info = snapshotInfo(snap);
const again: Detector = Detector.restore(snap);
const n: number = one.f + cols.f[0] + log.rows + audit.report.rows + audit2.report.stats.gpsEpochs + info.version + again.rowCount();
await loadLab();
tuned.free();
det.free();
export { n };
