// smc-bench-job-page: how long a finished job's history page takes to load
// in headless Chromium, for the paper's job-shop job (52 s of machine time
// under SMC II, a pass added) cut by a real edge at --speedup 8, against the
// cell's database (smc-dashboard --cell-db). Reports the API's answer time
// and size, and the page's time from navigation to drawn, over --runs loads.
//
//   smc-bench-job-page [--runs 10]

import { execFileSync } from 'node:child_process';
import { mkdtempSync, rmSync, writeFileSync } from 'node:fs';
import { createRequire } from 'node:module';
import { tmpdir } from 'node:os';
import { dirname, join, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';

import { CHROMIUM_ARGS, Proc, stopAll } from '../../browser/processes.mjs';
import { benchArgs } from './args.mjs';

const { runs: RUNS } = benchArgs(
  'smc-bench-job-page',
  "How long a finished job's history page takes to load in headless Chromium.",
  { runs: { what: 'page loads timed', dflt: 10, min: 1, max: 1000 } });
const BIN = process.env.SMC_BIN_DIR;
const require = createRequire(join(process.env.SMC_NODE_MODULES, 'x.js'));
const { chromium } = require('playwright-core');
const source = resolve(dirname(fileURLToPath(import.meta.url)), '..', '..', '..');
const pct = (v, p) => [...v].sort((a, b) => a - b)[Math.min(v.length - 1, Math.round(p * (v.length - 1)))];

async function main() {
  const dir = mkdtempSync(join(tmpdir(), 'smc-bench-job-page-'));
  let context = null;
  try {
    const partition = `bench-job-page-${process.pid}`;
    const db = join(dir, 'cell.db');
    execFileSync(`${BIN}/smc-cell`, ['db', 'init', '--db', db, '--seed'], { stdio: 'ignore' });
    new Proc('smc-cell', `${BIN}/smc-cell`, ['serve', '--db', db, '--partition', partition]);
    new Proc('smc-edge', `${BIN}/smc-edge`, ['run', '--machine', 'mill-1', '--partition', partition,
      '--speedup', '8', '--no-realtime', '--mill-model', join(source, 'cell/models/paper_face_mill.textproto')]);
    const dash = new Proc('dashboard', `${BIN}/smc-dashboard`,
      ['--http', '127.0.0.1:0', '--partition', partition, '--cell-db', db, '--log-level', 'warn']);
    const [, url] = await dash.waitFor(/listening on (http:\/\/\S+)/, 10000);
    const job = join(dir, 'job.textproto');
    writeFileSync(job, 'part_id: "housing-js"\nmachine_id: "mill-1"\n');
    const id = execFileSync(`${BIN}/smc-cell`, ['job', 'submit', job, '--db', db]).toString().split(' ')[0];
    process.stderr.write(`${id}: cutting the paper's job-shop job at 8x\n`);
    const deadline = Date.now() + 60000;
    for (;;) {
      const list = execFileSync(`${BIN}/smc-cell`, ['job', 'list', '--db', db]).toString();
      if (new RegExp(`${id}\\s+done`).test(list)) break;
      if (Date.now() > deadline) throw new Error(`${id} not done within 60 s:\n${list}`);
      await new Promise((r) => setTimeout(r, 500));
    }
    await new Promise((r) => setTimeout(r, 1500));  // the trailing revolutions written
    context = await chromium.launchPersistentContext(join(dir, 'profile'), {
      executablePath: '/usr/bin/chromium', headless: true, args: CHROMIUM_ARGS,
      viewport: { width: 1600, height: 1100 },
    });
    const page = context.pages()[0] ?? await context.newPage();
    const api = [];
    const drawn = [];
    let info = null;
    for (let run = 0; run < RUNS; run++) {
      await page.goto('about:blank');
      const t0 = Date.now();
      await page.goto(`${url}#/job/${id}`);
      await page.waitForSelector(`#job-view[data-ready="true"]`, { timeout: 10000 });
      drawn.push(Date.now() - t0);
      info = await page.evaluate(async (job) => {
        const t = performance.now();
        const r = await fetch(`/api/jobs/${job}/history`);
        const body = await r.text();
        return { ms: performance.now() - t, bytes: body.length, revs: JSON.parse(body).revolutions.count,
                 end: JSON.parse(body).revolutions.t.at(-1), page: window.smcApp.jobLoadMs };
      }, id);
      api.push(info.ms);
    }
    console.log(`job ${id}: ${info.revs} revolutions recorded (to ${info.end.toFixed(1)} s of machine time), ` +
      `history JSON ${(info.bytes / 1024).toFixed(0)} kB`);
    console.log(`API answer (in the page): p50 ${pct(api, 0.5).toFixed(1)} ms, max ${Math.max(...api).toFixed(1)} ms`);
    console.log(`page load, navigation to drawn (${RUNS} loads): p50 ${pct(drawn, 0.5)} ms, ` +
      `max ${Math.max(...drawn)} ms; goal < 1000 ms: ${Math.max(...drawn) < 1000 ? 'met' : 'NOT met'}`);
  } finally {
    if (context) await context.close().catch(() => {});
    await stopAll();
    rmSync(dir, { recursive: true, force: true });
  }
}

main().catch((e) => { console.error(e); process.exit(1); });
