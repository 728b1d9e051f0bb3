// smc-bench-dashboard-browser: latency from a force summary's write on DDS
// (its DDS source timestamp, the edge's wall clock) to its arrival in the
// page (the EventSource handler, browser wall clock; same host), with 10
// mills streaming from the cell fixture (cell.mjs), two pages open in
// headless Chromium: the cell view (every mill) and a mill view (one mill
// with raw forces, Grafcet, charts). Also the CPU of smc-dashboard and of
// the publisher over the same window.
//
//   smc-bench-dashboard-browser [--mills 10] [--seconds 20]

import { readFileSync, mkdtempSync, rmSync } from 'node:fs';
import { createRequire } from 'node:module';
import { tmpdir } from 'node:os';
import { join } from 'node:path';

import { startCell } from '../../browser/cell.mjs';
import { CHROMIUM_ARGS, Proc, stopAll } from '../../browser/processes.mjs';
import { benchArgs } from './args.mjs';

const { mills: MILLS, seconds: SECONDS } = benchArgs(
  'smc-bench-dashboard-browser',
  "Latency from a force summary's write on DDS to its arrival in the page (headless Chromium),\n" +
    'with the CPU of smc-dashboard and of the publisher.',
  {
    mills: { what: 'mills streaming', dflt: 10, min: 1, max: 50 },
    seconds: { what: 'seconds measured', dflt: 20, min: 2, max: 600 },
  });
const BIN = process.env.SMC_BIN_DIR;
const require = createRequire(join(process.env.SMC_NODE_MODULES, 'x.js'));
const { chromium } = require('playwright-core');

const ticks = Number(process.env.SMC_CLK_TCK ?? 100);
function cpuSeconds(pid) {
  const stat = readFileSync(`/proc/${pid}/stat`, 'utf8');
  const f = stat.slice(stat.lastIndexOf(')') + 2).split(' ');
  return (Number(f[11]) + Number(f[12])) / ticks;  // utime, stime
}
const pct = (v, p) => {
  const s = [...v].sort((a, b) => a - b);
  return s.length ? s[Math.min(s.length - 1, Math.round(p * (s.length - 1)))] : NaN;
};

async function main() {
  const tmp = mkdtempSync(join(tmpdir(), 'smc-bench-browser-'));
  let context = null;
  try {
    const partition = `bench-browser-${process.pid}-${Date.now()}`;
    // Many mills, cheaply: the fake cell (SMC_TEST_CELL=real for the real one).
    const cell = await startCell({ binDir: BIN, partition, workDir: tmp, mills: MILLS,
                                   kind: process.env.SMC_TEST_CELL ?? 'fake' });
    const dash = new Proc('dashboard', `${BIN}/smc-dashboard`,
      ['--http', '127.0.0.1:0', '--partition', partition, '--log-level', 'warn']);
    const [, url] = await dash.waitFor(/listening on (http:\/\/\S+)/, 10000);
    context = await chromium.launchPersistentContext(join(tmp, 'profile'), {
      executablePath: '/usr/bin/chromium', headless: true, args: CHROMIUM_ARGS,
      viewport: { width: 1600, height: 1100 },
    });
    const cellPage = context.pages()[0] ?? await context.newPage();
    await cellPage.goto(`${url}#/`);
    const millPage = await context.newPage();
    await millPage.goto(`${url}#/mill/mill-1`);
    for (const p of [cellPage, millPage]) {
      await p.waitForFunction(() => window.smcStats.summaries() > 50, null, { timeout: 15000 });
    }
    await new Promise((r) => setTimeout(r, 2000));  // warm-up
    for (const p of [cellPage, millPage]) await p.evaluate(() => window.smcStats.reset());
    const pids = { dashboard: dash.child.pid, publisher: cell.log.child.pid };
    const cpu0 = Object.fromEntries(Object.entries(pids).map(([k, pid]) => [k, cpuSeconds(pid)]));
    const t0 = performance.now();
    await new Promise((r) => setTimeout(r, SECONDS * 1000));
    const wall = (performance.now() - t0) / 1000;
    const cpu = Object.fromEntries(Object.entries(pids).map(([k, pid]) => [k, (cpuSeconds(pid) - cpu0[k]) / wall]));
    const cellLat = await cellPage.evaluate(() => window.smcStats.latencies());
    const millLat = await millPage.evaluate(() => window.smcStats.latencies());

    console.log(`smc-bench-dashboard-browser: ${MILLS} mills (${cell.kind} cell), ${SECONDS} s, ` +
      'headless Chromium: cell view + mill-1 view (raw forces)');
    console.log('force summary: DDS source time -> page EventSource handler');
    const row = (name, v) => console.log(`  ${name.padEnd(34)} n ${String(v.length).padStart(6)}   ` +
      `p50 ${pct(v, 0.5).toFixed(2).padStart(7)} ms   p99 ${pct(v, 0.99).toFixed(2).padStart(7)} ms   ` +
      `max ${Math.max(...v).toFixed(2).padStart(7)} ms`);
    row('cell view (all mills)', cellLat);
    row('mill view (mill-1 + raw)', millLat);
    console.log(`  summaries per second in the cell view: ${(cellLat.length / wall).toFixed(1)} ` +
      `(${MILLS} mills x 25 = ${MILLS * 25} written)`);
    console.log(`CPU, % of one core: smc-dashboard ${(100 * cpu.dashboard).toFixed(1)} %, ` +
      `publisher (${cell.kind}) ${(100 * cpu.publisher).toFixed(1)} %`);
  } finally {
    if (context) await context.close().catch(() => {});
    await stopAll();
    rmSync(tmp, { recursive: true, force: true });
  }
}

main().catch(async (e) => {
  console.error(e);
  await stopAll();
  process.exit(1);
});
