// The node benchmarks' flags: whole numbers, each with a default and a
// range. --help prints them and exits 0; an unknown flag, a flag without its
// value or a value out of range is refused, naming it, with exit status 2.
import { parseArgs } from 'node:util';

// flags: { name: { what, dflt, min, max } }. Returns { name: value }.
export function benchArgs(program, about, flags) {
  const names = Object.keys(flags);
  const usage = [
    `usage: ${program} ${names.map((f) => `[--${f} N]`).join(' ')}`,
    about,
    '',
    ...names.map((f) => {
      const d = flags[f];
      return `  --${f} N`.padEnd(16) + `${d.what} (${d.dflt}; ${d.min}-${d.max})`;
    }),
  ].join('\n');
  let values;
  try {
    const options = { help: { type: 'boolean', short: 'h' } };
    for (const f of names) options[f] = { type: 'string' };
    ({ values } = parseArgs({ options }));
  } catch (e) {
    console.error(`${program}: ${e.message}\n${usage}`);
    process.exit(2);
  }
  if (values.help) {
    console.log(usage);
    process.exit(0);
  }
  const out = {};
  for (const f of names) {
    const d = flags[f];
    const text = values[f];
    const v = text === undefined ? d.dflt : Number(text);
    if (!Number.isInteger(v) || v < d.min || v > d.max) {
      console.error(`${program}: --${f} ${text}: a whole number from ${d.min} to ${d.max}`);
      process.exit(2);
    }
    out[f] = v;
  }
  return out;
}
