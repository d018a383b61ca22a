// Browser entry (bundlers and a plain <script type="module">): the .wasm
// bytes ship inside JS modules (base64), so any bundler takes them with no
// configuration and a static folder needs no server set-up. `await init()`
// once before the first call; `await loadAudit()` before an audit API
// (auditBytes, Auditor, StreamAuditor, metrics) and `await loadLab()` before
// a lab API (each module's bytes are imported only then).
import { loader } from './loader.js';

function decode(b64) {
  if (typeof Uint8Array.fromBase64 === 'function') return Uint8Array.fromBase64(b64);
  const s = atob(b64);
  const out = new Uint8Array(s.length);
  for (let i = 0; i < s.length; i++) out[i] = s.charCodeAt(i);
  return out;
}

loader.core = async () => decode((await import('./navguard_core_wasm.js')).default);
loader.audit = async () => decode((await import('./navguard_audit_wasm.js')).default);
loader.lab = async () => decode((await import('./navguard_lab_wasm.js')).default);

export * from './api.js';
export { default } from './api.js';
