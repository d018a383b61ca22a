// Node entry (ESM; node.cjs is this file bundled for `require`): the .wasm
// files are read from the package folder, each on first use, so
// `init()` is optional and the audit and lab modules load only when one of
// their APIs is used.
import { readFileSync } from 'node:fs';
import { loader } from './loader.js';

const file = (name) => readFileSync(new URL(name, import.meta.url));
loader.coreSync = () => file('./navguard_core_bg.wasm');
loader.auditSync = () => file('./navguard_audit_bg.wasm');
loader.labSync = () => file('./navguard_lab_bg.wasm');
loader.core = async () => loader.coreSync();
loader.audit = async () => loader.auditSync();
loader.lab = async () => loader.labSync();

export * from './api.js';
export { default } from './api.js';
