// Where the .wasm bytes come from, filled in by the entry file (node.js or
// navguard.js): `core()` / `audit()` / `lab()` give them asynchronously;
// `coreSync()` / `auditSync()` / `labSync()`, where the platform can,
// synchronously (Node).
export const loader = {
  core: null,
  audit: null,
  lab: null,
  coreSync: null,
  auditSync: null,
  labSync: null,
};
