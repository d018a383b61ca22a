// Command-line flags checked against each command's own list: an unknown or
// misspelt flag, a missing value and a value of the wrong type are errors
// (exit 2) that name the flag, never silently ignored or read as NaN.
import { CliError } from './files.mjs';

/** Value kinds: `bool` takes no value; the others take the next argument. */
const PARSERS = {
  string: (v) => v,
  path: (v) => {
    if (v === '') throw new Error('must be a non-empty path');
    return v;
  },
  /** A whole number >= 1. */
  count: (v) => {
    if (!/^\d+$/.test(v) || Number(v) < 1 || !Number.isSafeInteger(Number(v))) throw new Error('must be a whole number >= 1');
    return Number(v);
  },
  /** A whole number >= 0. */
  seed: (v) => {
    if (!/^\d+$/.test(v) || !Number.isSafeInteger(Number(v))) throw new Error('must be a whole number >= 0');
    return Number(v);
  },
  list: (v) => {
    const items = v.split(',').map((s) => s.trim());
    if (items.some((s) => s === '')) throw new Error('must be a comma-separated list with no empty item');
    return items;
  },
};

/** Levenshtein distance, for "did you mean". */
function distance(a, b) {
  const d = Array.from({ length: a.length + 1 }, (_, i) => [i, ...Array(b.length).fill(0)]);
  for (let j = 1; j <= b.length; j++) d[0][j] = j;
  for (let i = 1; i <= a.length; i++) {
    for (let j = 1; j <= b.length; j++) {
      d[i][j] = Math.min(d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + (a[i - 1] === b[j - 1] ? 0 : 1));
    }
  }
  return d[a.length][b.length];
}

/** The closest known name within 3 edits, or null. */
export function suggest(name, known) {
  let best = null, bd = 4;
  for (const k of known) {
    const dist = distance(name, k);
    if (dist < bd) { bd = dist; best = k; }
  }
  return best;
}

/**
 * Parse `argv` for `command` against `spec` (flag name -> value kind).
 * Returns `{ pos, opt }`; `--help`/`-h` is always accepted. `--flag=value`
 * and `--flag value` are both accepted.
 */
export function parseArgs(command, argv, spec) {
  const pos = [], opt = {};
  const known = Object.keys(spec);
  for (let i = 0; i < argv.length; i++) {
    const a = argv[i];
    if (a === '-h' || a === '--help') { opt.help = true; continue; }
    if (a === '--') { pos.push(...argv.slice(i + 1)); break; }
    if (!a.startsWith('-') || a === '-') { pos.push(a); continue; }
    const eq = a.indexOf('=');
    const name = a.startsWith('--') ? a.slice(2, eq < 0 ? undefined : eq) : a.slice(1);
    const kind = Object.hasOwn(spec, name) ? spec[name] : undefined;
    if (kind === undefined) {
      const s = suggest(name, known);
      throw new CliError(`${command}: unknown option ${a.split('=')[0]}${s ? ` (did you mean --${s}?)` : ''}; see 'navguard ${command} --help'`);
    }
    if (Object.hasOwn(opt, name)) throw new CliError(`${command}: option --${name} given twice`);
    if (kind === 'bool') {
      if (eq >= 0) throw new CliError(`${command}: option --${name} takes no value`);
      opt[name] = true;
      continue;
    }
    let value;
    if (eq >= 0) value = a.slice(eq + 1);
    else if (i + 1 < argv.length) value = argv[++i];
    else throw new CliError(`${command}: option --${name} needs a value`);
    try { opt[name] = PARSERS[kind](value); } catch (e) { throw new CliError(`${command}: --${name} ${JSON.stringify(value)}: ${e.message}`); }
  }
  return { pos, opt };
}
