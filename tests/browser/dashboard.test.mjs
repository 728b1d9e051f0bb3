// Browser test of smc-dashboard, in Debian's headless Chromium driven by
// playwright-core, over HTTPS (a certificate from the project's web CA,
// deploy/security/pki.sh https; Chromium trusts that one key, pinned with
// --ignore-certificate-errors-spki-list, and nothing else) with a hashed
// token file. Against a running cell with simulated mills (cell.mjs):
//
//   1. the page loads and draws mill-1's Grafcet from its SupervisorConfig;
//   2. the live F_Y chart receives new points (machine time advances);
//   3. the Grafcet view follows the supervisor: the steps highlighted in the
//      page equal the active steps seen on DDS by an independent probe, for
//      at least two different situations;
//   4. read-only until signed in; a feed hold clicked in the page puts the
//      edge in feed hold, checked on DDS (the command with the operator's
//      name, then the edge's situation: step 5 active, module C), and the
//      page shows it; release brings it back;
//   5. a screenshot is saved: $SMC_ARTIFACTS_DIR/dashboard.png;
//   6. mill-2 cuts the cover under SMC II+: its chatter's remedy is the new
//      spindle speed, and the tooth that breaks 5 s into the job shows as
//      "tool broken" on its card and in its view (dashboard-breakage.png),
//      and the catalog shows a machine whose wideband channel the cell warns
//      of, the warning under its channel;
//   7. the failed job's history page, from the cell's database: charts,
//      events, plan and programs, its CSV export, and the same page again
//      after the dashboard restarts (dashboard-job.png; load time printed);
//   8. a planned SMC I job's page shows its plan on the lobe diagram with
//      the margin (dashboard-job-smc1.png).
//
// Environment (ctest sets it): SMC_BIN_DIR, SMC_NODE_MODULES (playwright-core
// from npm ci), SMC_ARTIFACTS_DIR, CYCLONEDDS_URI (loopback profile).
// Every process started here is stopped on success, failure or timeout.

import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import { mkdtempSync, rmSync, writeFileSync, mkdirSync, chmodSync } from 'node:fs';
import { createRequire } from 'node:module';
import { tmpdir } from 'node:os';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';

import { startCell } from './cell.mjs';
import { CHROMIUM_ARGS, Proc, stopAll } from './processes.mjs';

const BIN = process.env.SMC_BIN_DIR ?? 'build/release/bin';
const SOURCE = join(dirname(fileURLToPath(import.meta.url)), '..', '..');
const ARTIFACTS = process.env.SMC_ARTIFACTS_DIR ?? 'build/release/artifacts';
const require = createRequire(join(process.env.SMC_NODE_MODULES ?? 'node_modules', 'x.js'));
const { chromium } = require('playwright-core');

const TOKEN = 'browser-test-token-5f2c9a71d3';
const DEADLINE_MS = 58000;

// smc2.grafcet declares steps 1..6 in order: step index i is step number i + 1.
const stepsOfMask = (mask) => [...Array(64).keys()].filter((i) => (BigInt(mask) >> BigInt(i)) & 1n)
  .map((i) => i + 1);

function step(text) {
  console.log(`[browser test] ${text}`);
}

let context = null;  // the browser, closed whatever happens
// The test's files (tokens, PKI, the browser's profile, the cell's database),
// removed whatever happens.
const tmp = mkdtempSync(join(tmpdir(), 'smc-browser-'));
async function cleanUp() {
  if (context) await context.close().catch(() => {});
  await stopAll();
  rmSync(tmp, { recursive: true, force: true });
}

async function main() {
  const partition = `browser-${process.pid}-${Date.now()}`;
  const pageErrors = [];
  try {
    const tokens = join(tmp, 'tokens');
    writeFileSync(tokens, execFileSync(`${BIN}/smc-dashboard`, ['--hash-token', 'alice'], { input: `${TOKEN}\n` }));
    chmodSync(tokens, 0o600);
    // HTTPS: the dashboard's certificate for 127.0.0.1, and the SHA-256 of
    // its public key, the one key Chromium is told to accept.
    execFileSync(join(SOURCE, 'deploy/security/pki.sh'), ['https', join(tmp, 'pki'), 'dashboard', '127.0.0.1']);
    const cert = join(tmp, 'pki/dashboard/https.pem');
    const spki = execFileSync('sh', ['-c', `openssl x509 -in '${cert}' -pubkey -noout | openssl pkey -pubin -outform der | openssl dgst -sha256 -binary | base64`]).toString().trim();

    step(`partition ${partition}: probe, cell and mills, dashboard`);
    const probe = new Proc('probe', `${BIN}/smc-dashboard-probe`, ['--partition', partition, '--mill', 'mill-1']);
    await probe.waitFor(/^ready$/, 10000);
    const cell = await startCell({ binDir: BIN, partition, workDir: tmp, mills: 2, breakage: true, channelNote: true });
    const dashArgs = ['--http', '127.0.0.1:0', '--partition', partition, '--token-file', tokens,
      '--cell-db', cell.db, '--tls-cert', cert, '--tls-key', join(tmp, 'pki/dashboard/https.key')];
    const dash = new Proc('dashboard', `${BIN}/smc-dashboard`, dashArgs);
    const [, url] = await dash.waitFor(/listening on (https:\/\/\S+)/, 10000);

    step(`chromium on ${url}`);
    context = await chromium.launchPersistentContext(join(tmp, 'profile'), {
      executablePath: '/usr/bin/chromium', headless: true,
      args: [...CHROMIUM_ARGS, `--ignore-certificate-errors-spki-list=${spki}`],
      viewport: { width: 1600, height: 1150 },
    });
    const page = context.pages()[0] ?? await context.newPage();
    page.on('pageerror', (e) => pageErrors.push(e.message));
    page.on('console', (m) => {
      // The refused command below is meant to log a 401.
      if (m.type() === 'error' && !m.text().includes('status of 401')) pageErrors.push(m.text());
    });
    await page.goto(`${url}#/mill/mill-1`);

    step('1. the page loads and draws the Grafcet of mill-1');
    await page.waitForSelector('#mill-view[data-mill="mill-1"]');
    await page.waitForFunction(() => document.querySelectorAll('svg.grafcet g.step').length === 6, null,
      { timeout: 15000 });
    assert.equal(await page.locator('#stream-state').textContent(), 'live');

    step('2. the live chart receives new points');
    await page.waitForFunction(() => window.smcApp.points('mill-1') > 5, null, { timeout: 10000 });
    const before = await page.evaluate(() => ({ n: window.smcApp.points('mill-1'), t: window.smcApp.lastTime('mill-1') }));
    await page.waitForFunction((b) => window.smcApp.points('mill-1') >= b.n + 10 && window.smcApp.lastTime('mill-1') > b.t + 0.3,
      before, { timeout: 10000 });
    assert.ok(await page.locator('#force-chart canvas').count() > 0, 'the F_Y chart is drawn');
    assert.ok(await page.locator('#power-chart canvas').count() > 0, 'the spindle power chart is drawn');
    await page.waitForFunction(() => /spindle power\s*\d+ W of \d+ W/.test(
      document.querySelector('#mill-facts')?.textContent ?? ''), null, { timeout: 10000 });

    step('3. the Grafcet view follows the supervisor (page vs DDS)');
    const seen = new Set();
    const until = Date.now() + 20000;
    while (seen.size < 2 && Date.now() < until) {
      const dds = probe.lines.filter((l) => l.startsWith('situation mill-1 ')).at(-1);
      const onPage = await page.evaluate(() =>
        [...document.querySelectorAll('svg.grafcet g.step.active')].map((g) => Number(g.dataset.step)));
      if (dds) {
        const expected = stepsOfMask(dds.match(/mask=(0x[0-9a-f]+)/)[1]);
        if (JSON.stringify(expected) === JSON.stringify(onPage)) seen.add(onPage.join(','));
      }
      await page.waitForTimeout(40);
    }
    assert.ok(seen.size >= 2, `page matched DDS in ${seen.size} situation(s) only: ${[...seen]}`);

    step('4. read-only until signed in; then feed hold from the page, checked on DDS');
    assert.equal(await page.locator('#btn-feed-hold').isDisabled(), true, 'feed hold is disabled without a token');
    const refused = await page.evaluate(async () => (await fetch('/api/mills/mill-1/commands', {
      method: 'POST', headers: { 'Content-Type': 'application/json' }, body: '{"action":"feed_hold_on"}' })).status);
    assert.equal(refused, 401);
    await page.fill('#token-input', TOKEN);
    await page.click('#signin button[type=submit]');
    await page.waitForSelector('#operator-name:text("alice")');
    await page.waitForFunction(() => !document.querySelector('#btn-feed-hold').disabled, null, { timeout: 5000 });
    // Hold while cutting (step 4, in contact), as in the paper's runs: F_Y
    // then stays at its last value while module I is off.
    await page.waitForFunction(() => window.smcApp.activeSteps('mill-1').includes(4) &&
      window.smcApp.store.mills.get('mill-1').summary?.in_contact, null, { timeout: 20000 });
    const mark = probe.lines.length;
    await page.click('#btn-feed-hold');
    await probe.waitFor(/^command mill-1 OP_FEED_HOLD_ON alice \d+$/, 5000, mark);
    await probe.waitFor(/^situation mill-1 mask=0x10 modules=ABC$/, 5000, mark);  // step 5, module C
    await probe.waitFor(/^status mill-1 EDGE_FEED_HOLD$/, 5000, mark);
    assert.equal(probe.lines.slice(0, mark).filter((l) => l.startsWith('command ')).length, 0,
      'no command reached DDS before the signed-in click');
    await page.waitForSelector('svg.grafcet g.step.active[data-step="5"]', { timeout: 5000 });
    await page.waitForSelector('#edge-badge [data-edge-state="EDGE_FEED_HOLD"]', { timeout: 5000 });
    await page.waitForSelector('.toast.ok', { timeout: 5000 });

    // The part program panel: the configuration in force's G-code, or says
    // there is none.
    await page.waitForFunction(() => {
      const box = document.querySelector('#program-view');
      return box && (box.querySelector('pre.gcode') || box.textContent.includes('No G-code'));
    }, null, { timeout: 5000 });

    step('5. screenshot');
    await page.waitForTimeout(1200);  // let the feed-hold span show on the chart
    mkdirSync(ARTIFACTS, { recursive: true });
    const shot = join(ARTIFACTS, 'dashboard.png');
    await page.screenshot({ path: shot, fullPage: true });
    step(`saved ${shot}`);

    const mark2 = probe.lines.length;
    await page.click('#btn-release');
    await probe.waitFor(/^command mill-1 OP_FEED_HOLD_OFF alice \d+$/, 5000, mark2);
    await probe.waitFor(/^situation mill-1 mask=0x[0-9a-f]+ modules=AB(?!C)/, 5000, mark2);
    await page.waitForFunction(() => !document.querySelector('svg.grafcet g.step.active[data-step="5"]'), null,
      { timeout: 5000 });

    step('6. SMC II+ on mill-2: the speed change and the broken tooth');
    await page.goto(`${url}#/`);
    await page.waitForSelector('.mill-card[data-mill="mill-2"] .breakage-flag', { timeout: 20000 });
    await page.goto(`${url}#/mill/mill-2`);
    await page.waitForSelector('#mill-view[data-mill="mill-2"]');
    await page.waitForFunction(() => /tool broken\s*tool breakage at 5\.\d+ s/.test(
      document.querySelector('#breakage')?.textContent ?? ''), null, { timeout: 5000 });
    await page.waitForFunction(() => /spindle speed → 2700 rpm/.test(
      document.querySelector('#chatter-list')?.textContent ?? ''), null, { timeout: 5000 });
    await page.screenshot({ path: join(ARTIFACTS, 'dashboard-breakage.png'), fullPage: true });
    await page.goto(`${url}#/`);
    await page.waitForSelector('.mill-card[data-mill="mill-2"]', { timeout: 5000 });
    // The cell's catalog, read-only: its machines with their edges, and what
    // a job of each part would get and why -- here that the parts' tool is
    // retired, since mill-2 found it broken.
    await page.waitForFunction(() => {
      const t = document.querySelector('#catalog')?.textContent ?? '';
      return t.includes('mill-2') && t.includes('bracket-tl') && t.includes('housing-js') &&
        t.includes('cover-jsp') && t.includes('default tool fm-r25-4t is retired') &&
        t.includes('wideband F_y (E)') && t.includes("cell's default");
    }, null, { timeout: 5000 });
    // mill-9's channel, with the cell's warning under it.
    const mill9 = await page.locator('#catalog tr', { hasText: 'slow-channel mill' }).textContent();
    assert.match(mill9, /2 kHz, order-4 filter at 500 Hz/);
    assert.match(mill9, /warning with model mill-9\.tap: module E's wideband channel \(2 kHz through an order-4 filter at 500 Hz\) takes the structure's y mode at 653 Hz 9\.7 dB down/);
    await page.screenshot({ path: join(ARTIFACTS, 'dashboard-cell.png'), fullPage: true });

    step('7. the failed job\'s history page, its CSV, and again after a dashboard restart');
    const jobId = await page.evaluate(() => window.smcApp.store.mills.get('mill-2').breakage.job_id);
    const checkHistory = async (base) => {
      await page.goto(`${base}#/job/${jobId}`);
      await page.waitForSelector(`#job-view[data-job="${jobId}"][data-ready="true"]`, { timeout: 5000 });
      const ms = await page.evaluate(() => window.smcApp.jobLoadMs);
      step(`   history page of ${jobId} drawn in ${ms.toFixed(0)} ms`);
      assert.ok(ms < 1000, `history page took ${ms} ms`);
      assert.ok(await page.locator('#job-force canvas').count() > 0, 'the F_Y chart is drawn');
      assert.ok(await page.locator('#job-power canvas').count() > 0, 'the power chart is drawn');
      const text = await page.locator('#job-view').textContent();
      for (const want of ['tool breakage at 5.', 'spindle speed changed to 2700 rpm', 'SMC II+ on mill-2',
        'smc2_plus.grafcet', 'revision 1']) {
        assert.ok(text.includes(want), `the history page shows "${want}"`);
      }
      const csv = await page.evaluate(async (id) => {
        const r = await fetch(`/api/jobs/${id}/history.csv`);
        return { status: r.status, type: r.headers.get('content-type'), body: await r.text() };
      }, jobId);
      assert.equal(csv.status, 200);
      assert.ok(csv.type.startsWith('text/csv'), csv.type);
      const lines = csv.body.trim().split('\n');
      assert.ok(lines[0].startsWith('job_id,attempt,t_s,'), lines[0]);
      const recorded = await page.evaluate(() => Number(document.querySelector('#job-facts').textContent.match(/revolutions recorded\s*(\d+)/)[1]));
      assert.equal(lines.length - 1, recorded, 'one CSV row per recorded revolution');
      assert.ok(recorded > 50, `${recorded} revolutions recorded`);
    };
    await checkHistory(url);
    await page.screenshot({ path: join(ARTIFACTS, 'dashboard-job.png'), fullPage: true });
    await dash.stop();
    const dash2 = new Proc('dashboard-2', `${BIN}/smc-dashboard`, dashArgs);
    const [, url2] = await dash2.waitFor(/listening on (https:\/\/\S+)/, 10000);
    await checkHistory(url2);

    step('8. the planned SMC I job on its lobe diagram');
    await page.waitForFunction(() => [...window.smcApp.store.jobs.values()].some(
      (j) => j.status?.job?.part_id === 'bracket-tl' && j.status?.variant === 'SMC_I'), null, { timeout: 10000 });
    const smc1 = await page.evaluate(() => [...window.smcApp.store.jobs.values()].find(
      (j) => j.status?.job?.part_id === 'bracket-tl').job_id);
    await page.goto(`${url2}#/job/${smc1}`);
    await page.waitForSelector(`#job-view[data-job="${smc1}"][data-ready="true"]`, { timeout: 5000 });
    await page.waitForSelector('#job-lobes-panel:not([hidden]) #job-lobes canvas', { timeout: 10000 });
    const lobeText = await page.locator('#job-lobes-text').textContent();
    assert.match(lobeText, /planned 1\.00 mm per pass at 1500 rpm; critical depth there [\d.]+ mm by the lobes, [\d.]+ mm by the plan's time-domain check; margin 0\.\d+/);
    await page.screenshot({ path: join(ARTIFACTS, 'dashboard-job-smc1.png'), fullPage: true });

    assert.deepEqual(pageErrors, [], 'no errors in the page');
    step('PASS');
  } finally {
    await cleanUp();
  }
}

const watchdog = setTimeout(async () => {
  console.error(`[browser test] FAIL: not done within ${DEADLINE_MS} ms`);
  await cleanUp();
  process.exit(1);
}, DEADLINE_MS);
for (const sig of ['SIGINT', 'SIGTERM']) {
  process.on(sig, async () => {
    await cleanUp();
    process.exit(1);
  });
}

main().then(() => {
  clearTimeout(watchdog);
  process.exit(0);
}, (e) => {
  clearTimeout(watchdog);
  console.error(`[browser test] FAIL: ${e.stack ?? e}`);
  process.exit(1);
});
