// A log no reader can read is a JS Error whose message names the line and
// column (CSV) or what was read (binary logs): LogError's text, the same in
// every entry point that reads a whole log.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { createRequire } from 'node:module';
import { join, dirname } from 'node:path';
import { fileURLToPath } from 'node:url';

const root = join(dirname(fileURLToPath(import.meta.url)), '..', '..');
const ng = createRequire(import.meta.url)(join(root, 'pkg'));
const enc = (s) => new TextEncoder().encode(s);
const NOT_ANY = 'not a ULog or DataFlash log, and not a navlog CSV: ';

// [bytes, message, whether a CSV header was read before the error]
const cases = [
  [enc('# c\nt,lat\n0,1\n0.1,abc\n'), `${NOT_ANY}line 4, column 'lat': cannot parse "abc" as a number`, true],
  [enc('t,lat\n0,1,2\n'), `${NOT_ANY}line 2: 3 fields, header has 2`, true],
  [enc('t,lat,lat\n'), `${NOT_ANY}header: column 'lat' appears twice`, false],
  [enc('t;lat\n0;1\n'), `${NOT_ANY}header: no 't' column (the delimiter must be a comma)`, false],
  [enc(''), `${NOT_ANY}no header row found (empty file or only comments)`, false],
  [Uint8Array.from([0x55, 0x4c, 0x6f, 0x67, 0x01, 0x12, 0x35, 0x01]), 'ULog header truncated (8 of 16 bytes)', false],
];

const throwsWith = (f, message) => assert.throws(f, (e) => e instanceof Error && e.message === message, message);

test('readLog and Auditor throw the log error as an Error', () => {
  for (const [bytes, message] of cases) {
    throwsWith(() => ng.readLog(bytes), message);
    throwsWith(() => new ng.Auditor(bytes), message);
  }
});

test('auditBytes (the streaming audit) says what the file is not only before a CSV header', () => {
  for (const [bytes, message, headerRead] of cases) {
    throwsWith(() => ng.auditBytes(bytes), headerRead ? message.slice(NOT_ANY.length) : message);
  }
});
