// A small promise wrapper over IndexedDB for the live session (no dependency).
//
// Database "navguard", version 1, two object stores with out-of-line keys:
//   live-session  key "current" -> {
//       schema: 1,
//       snapshot: Uint8Array,            Detector.snapshot() bytes
//       info: {version, crateVersion, bytes},
//       source: {kind:'sim', scenario, seed, name, rows}
//             | {kind:'file', name, size, lastModified, rows, fileStored},
//       nextRow,                         next source row to push
//       rowCount, stats,                 the snapshotted detector's counters
//       config, speed, savedAt (ms since the epoch), reason }
//   live-file     key "current" -> {name, size, lastModified, bytes: ArrayBuffer}
//                 (the replayed log itself, when it is under 50 MB)
export const DB_NAME = 'navguard';
export const DB_VERSION = 1;
export const SESSION = 'live-session';
export const FILE = 'live-file';
export const KEY = 'current';

let dbPromise = null;
let db = null; // the open connection, for writes that must start synchronously (pagehide)

export function openDb() {
  if (dbPromise) return dbPromise;
  dbPromise = new Promise((resolve, reject) => {
    if (typeof indexedDB === 'undefined') {
      reject(new Error('IndexedDB is not available in this browser'));
      return;
    }
    let r;
    try {
      r = indexedDB.open(DB_NAME, DB_VERSION);
    } catch (e) {
      reject(e);
      return;
    }
    r.onupgradeneeded = () => {
      const d = r.result;
      for (const s of [SESSION, FILE]) if (!d.objectStoreNames.contains(s)) d.createObjectStore(s);
    };
    r.onsuccess = () => {
      db = r.result;
      db.onversionchange = () => { db.close(); db = null; dbPromise = null; };
      db.onclose = () => { db = null; dbPromise = null; };
      resolve(db);
    };
    r.onerror = () => reject(r.error || new Error('IndexedDB open failed'));
    r.onblocked = () => reject(new Error('IndexedDB is blocked by another tab of this page'));
  });
  dbPromise.catch(() => { dbPromise = null; });
  return dbPromise;
}

// Run fn(store) in one transaction; resolves with fn's request result once
// the transaction has committed.
function run(d, store, mode, fn) {
  return new Promise((resolve, reject) => {
    let t;
    try {
      t = d.transaction(store, mode);
    } catch (e) {
      reject(e);
      return;
    }
    let result;
    const req = fn(t.objectStore(store));
    if (req) req.onsuccess = () => { result = req.result; };
    t.oncomplete = () => resolve(result);
    t.onerror = () => reject(t.error || new Error('IndexedDB transaction failed'));
    t.onabort = () => reject(t.error || new Error('IndexedDB transaction aborted'));
  });
}

export async function get(store, key = KEY) {
  return run(await openDb(), store, 'readonly', (s) => s.get(key));
}

export async function put(store, value, key = KEY) {
  return run(await openDb(), store, 'readwrite', (s) => s.put(value, key));
}

export async function del(store, key = KEY) {
  return run(await openDb(), store, 'readwrite', (s) => s.delete(key));
}

/** Start a put now, in this task, when the connection is already open (for
 *  pagehide, where awaiting first could be too late). Returns a promise or
 *  null when no connection is open. */
export function putNow(store, value, key = KEY) {
  if (!db) return null;
  const p = run(db, store, 'readwrite', (s) => s.put(value, key));
  p.catch(() => {});
  return p;
}
