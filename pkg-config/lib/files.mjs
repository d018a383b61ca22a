// File safety for the CLI: an output never overwrites an input, outputs are
// written atomically, and inputs are regular files of bounded size where the
// CLI reads them whole. Every failure is a `CliError` (one line, exit 2).
import { closeSync, fstatSync, openSync, readSync, readdirSync, renameSync, statSync, unlinkSync, writeSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { StringDecoder } from 'node:string_decoder';
import { basename, dirname, join } from 'node:path';

/** An error the CLI reports as one line on stderr with exit code 2. */
export class CliError extends Error {}

function describe(e) {
  if (e && e.code === 'ENOENT') return 'no such file or directory';
  if (e && e.code === 'EACCES') return 'permission denied';
  if (e && e.code === 'EISDIR') return 'is a directory';
  return e && e.message ? e.message : String(e);
}

/** `statSync` (following symlinks) or null when the path does not exist. */
function statOrNull(path) {
  try { return statSync(path); } catch (e) { if (e.code === 'ENOENT') return null; throw new CliError(`${path}: ${describe(e)}`); }
}

/** `fstatSync(fd)`, or null when the descriptor is not open. */
function fstatOrNull(fd) {
  try { return fstatSync(fd); } catch { return null; }
}

/** True when a and b are the same file: same device and inode, symlinks and
 * hard links included. */
export function sameFile(a, b) {
  return a !== null && b !== null && a.dev === b.dev && a.ino === b.ino;
}

/**
 * Refuse an output path that is (or resolves to) one of the inputs. `what`
 * names the flag in the message, e.g. `--per-sample`.
 */
export function refuseOverwrite(what, out, inputs) {
  const o = statOrNull(out);
  if (o === null) return;
  if (o.isDirectory()) throw new CliError(`${what} ${out}: is a directory`);
  for (const input of inputs) {
    if (sameFile(o, statOrNull(input))) throw new CliError(`${what} ${out}: is the input ${input}; refusing to overwrite it`);
  }
}

/**
 * Open an input that the CLI will read: it must exist and be a regular file
 * (a FIFO with no writer would block for ever, a device never ends). Returns
 * `{ fd, size }`. The file is opened first and checked through the open
 * descriptor, so a swap between check and read cannot slip a FIFO in.
 */
export function openInput(path) {
  let st = statOrNull(path);
  if (st === null) throw new CliError(`${path}: no such file`);
  if (!st.isFile()) throw new CliError(`${path}: not a regular file (${kindOf(st)})`);
  let fd;
  try { fd = openSync(path, 'r'); } catch (e) { throw new CliError(`${path}: ${describe(e)}`); }
  st = fstatSync(fd);
  if (!st.isFile()) { closeSync(fd); throw new CliError(`${path}: not a regular file (${kindOf(st)})`); }
  return { fd, size: st.size };
}

function kindOf(st) {
  if (st.isDirectory()) return 'a directory';
  if (st.isFIFO()) return 'a FIFO';
  if (st.isCharacterDevice() || st.isBlockDevice()) return 'a device';
  if (st.isSocket()) return 'a socket';
  return 'not a file';
}

/** Read a whole small input (a config, a model), refusing more than `limit` bytes. */
export function readSmall(path, limit, what) {
  const { fd, size } = openInput(path);
  try {
    if (size > limit) throw new CliError(`${what} ${path}: ${size} bytes, more than the ${limit}-byte limit`);
    const buf = Buffer.alloc(size);
    let n = 0;
    while (n < size) {
      const k = readSync(fd, buf, n, size - n, n);
      if (k === 0) break;
      n += k;
    }
    return buf.subarray(0, n).toString('utf8');
  } finally { closeSync(fd); }
}

let serial = 0;

const pause = new Int32Array(new SharedArrayBuffer(4));

/** Write all of `text` to a stream's descriptor, synchronously. A pipe
 * that Node made non-blocking (our own stdout, once used) takes part of a
 * write or none (EAGAIN) while its reader is behind: wait a millisecond
 * and go on. */
function writeStream(fd, text) {
  const buf = Buffer.from(text);
  for (let off = 0; off < buf.length;) {
    try { off += writeSync(fd, buf, off); } catch (e) {
      if (e.code !== 'EAGAIN') throw e;
      Atomics.wait(pause, 0, 0, 1);
    }
  }
}

/**
 * An output written atomically: the data goes to a temporary file beside the
 * target, which replaces the target by `rename` only on `commit()`. Until
 * then the target is untouched, so an interrupted or failed run leaves the
 * previous file (or none). `abort()` removes the temporary file.
 *
 * A stream (`/dev/stdout`, a pipe, a terminal) is written straight: there
 * is no file to replace, and a rename onto its name replaced the name
 * itself (run as root, `--per-sample /dev/stdout` turned the `/dev/stdout`
 * link into a regular file holding the output, and nothing reached the
 * pipe).
 */
export class AtomicOutput {
  constructor(path, what, inputs = []) {
    refuseOverwrite(what, path, inputs);
    this.path = path;
    this.what = what;
    this.gone = false;
    // A stream (a pipe, a terminal, `/dev/stdout`, a socket) exists and,
    // links followed, is neither a regular file nor a folder.
    const st = statOrNull(path);
    const stream = st !== null && !st.isFile() && !st.isDirectory();
    this.tmp = stream ? null : join(dirname(path), `.${basename(path)}.navguard-${process.pid}-${serial++}.tmp`);
    // Our own stdout or stderr by another name is written through its
    // descriptor: a socket (as Node's child processes get) cannot be
    // opened by name (ENXIO).
    this.own = stream ? [1, 2].find((fd) => sameFile(st, fstatOrNull(fd))) ?? null : null;
    if (this.own !== null) { this.fd = this.own; return; }
    try { this.fd = openSync(this.tmp ?? path, this.tmp ? 'wx' : 'w'); } catch (e) { throw new CliError(`${what} ${path}: ${describe(e)}`); }
  }

  write(text) {
    if (this.gone) return;
    try { if (this.tmp === null) writeStream(this.fd, text); else writeSync(this.fd, text); } catch (e) {
      // A stream's reader went away (`| head`): stop quietly, as stdout does.
      if (this.tmp === null && e.code === 'EPIPE') { this.gone = true; return; }
      this.abort();
      throw new CliError(`${this.what} ${this.path}: ${describe(e)}`);
    }
  }

  commit() {
    try {
      if (this.own === null) closeSync(this.fd);
      this.fd = null;
      if (this.tmp) renameSync(this.tmp, this.path);
    } catch (e) { this.abort(); throw new CliError(`${this.what} ${this.path}: ${describe(e)}`); }
  }

  abort() {
    if (this.fd !== null && this.own === null) { try { closeSync(this.fd); } catch { /* already closed */ } }
    this.fd = null;
    if (this.tmp) try { unlinkSync(this.tmp); } catch { /* never created or already renamed */ }
  }
}

/**
 * A private scratch file for the first pass of an `AtomicOutput`, read back
 * line by line for its second (`eachLine`) and removed by `remove()`. It
 * lies beside the output's temporary file, where the output itself will
 * need the room, or in the system's temporary folder for a stream.
 */
export class ScratchFile {
  constructor(out) {
    this.what = `${out.what} ${out.path}`;
    const dir = out.tmp === null ? tmpdir() : dirname(out.tmp);
    this.path = join(dir, `.${basename(out.path)}.navguard-${process.pid}-${serial++}.scratch`);
    try { this.fd = openSync(this.path, 'wx+'); } catch (e) { throw new CliError(`${this.what}: ${describe(e)}`); }
  }

  write(text) {
    try { writeSync(this.fd, text); } catch (e) { throw new CliError(`${this.what}: ${describe(e)}`); }
  }

  /** Call `fn(line)` on each line written, without its newline, reading
   * 1 MiB at a time (memory stays bounded whatever the file's size; 4 MiB
   * reads put 20–35 MB more on the peak RSS, in transient strings). */
  eachLine(fn) {
    const buf = Buffer.alloc(1 << 20);
    const text = new StringDecoder('utf8');
    let pos = 0, rest = '';
    for (;;) {
      let n;
      try { n = readSync(this.fd, buf, 0, buf.length, pos); } catch (e) { throw new CliError(`${this.what}: ${describe(e)}`); }
      if (n === 0) break;
      pos += n;
      const lines = (rest + text.write(buf.subarray(0, n))).split('\n');
      rest = lines.pop();
      for (const l of lines) fn(l);
    }
    if (rest !== '') fn(rest);
  }

  remove() {
    if (this.fd !== null) { try { closeSync(this.fd); } catch { /* already closed */ } this.fd = null; }
    try { unlinkSync(this.path); } catch { /* already removed */ }
  }
}

/** Write `text` to `path` atomically, refusing to overwrite any of `inputs`. */
export function writeAtomic(path, text, what, inputs = []) {
  const out = new AtomicOutput(path, what, inputs);
  out.write(text);
  out.commit();
}

/** The first bytes of a file look like a log navguard reads: a ULog or
 * DataFlash header, or a navlog CSV whose header (after `#` comments) has a
 * `t` column. */
export function sniffLog(path) {
  let fd;
  try { fd = openSync(path, 'r'); } catch { return false; }
  try {
    const head = Buffer.alloc(4096);
    const n = readSync(fd, head, 0, head.length, 0);
    if (n >= 7 && head.subarray(0, 7).equals(Buffer.from([0x55, 0x4c, 0x6f, 0x67, 0x01, 0x12, 0x35]))) return true;
    if (n >= 3 && head[0] === 0xa3 && head[1] === 0x95) return true;
    const text = head.subarray(0, n).toString('utf8');
    const header = text.split(/\r?\n/).find((l) => l.trim() !== '' && !l.startsWith('#'));
    return header !== undefined && header.split(',').map((c) => c.trim().toLowerCase()).includes('t');
  } finally { closeSync(fd); }
}

/**
 * Every log under `dir`, recursively, following symbolic links (each file
 * or folder once, by device and inode, so a link loop ends). Returns
 * `{ logs, skipped }`: `skipped` lists what was passed over and why (not a
 * regular file, not a log, a broken link).
 */
export function walkLogs(dir) {
  const logs = [], skipped = [], seen = new Map();
  const visit = (path, depth) => {
    let st;
    try { st = statSync(path); } catch (e) { skipped.push({ file: path, why: describe(e) }); return; }
    const id = `${st.dev}:${st.ino}`;
    if (seen.has(id)) {
      if (!st.isDirectory()) skipped.push({ file: path, why: `the same file as ${seen.get(id)}` });
      return;
    }
    seen.set(id, path);
    if (st.isDirectory()) {
      if (depth > 32) { skipped.push({ file: path, why: 'deeper than 32 folders' }); return; }
      let names;
      try { names = readdirSync(path).sort(); } catch (e) { skipped.push({ file: path, why: describe(e) }); return; }
      for (const name of names) visit(join(path, name), depth + 1);
    } else if (!st.isFile()) {
      skipped.push({ file: path, why: `not a regular file (${kindOf(st)})` });
    } else if (!sniffLog(path)) {
      skipped.push({ file: path, why: 'not a log (no ULog, DataFlash or navlog CSV header)' });
    } else {
      logs.push(path);
    }
  };
  visit(dir, 0);
  return { logs, skipped };
}
