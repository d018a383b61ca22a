// Where the .wasm bytes come from, filled in by the entry file (node.js or
// navguard.js): `core()` / `lab()` give them asynchronously; `coreSync()` /
// `labSync()`, where the platform can, synchronously (Node).
export const loader = {
  core: null,
  lab: null,
  coreSync: null,
  labSync: null,
};
