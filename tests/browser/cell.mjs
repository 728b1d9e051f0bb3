// "The cell and its mills" for browser tests and benchmarks, in one place.
//
// Default (SMC_TEST_CELL unset or "real"): the real processes, each in the
// test's DDS partition: a seeded cell database in a temporary folder,
// `smc-cell serve`, and one `smc-edge run --machine mill-N` per mill on the
// simulated mill (paced to the wall clock), with a job-shop job submitted
// for mill-1 so that it runs SMC II (the smc2 Grafcet) and cuts.
//
// SMC_TEST_CELL=fake: smc-dashboard-fake-mill, a test tool that plays the
// cell and N edges on the same topics (for the dashboard's own benchmarks,
// which need many mills cheaply).
//
// Mills are named mill-1 .. mill-N; mill-1 runs SMC II. With breakage: true
// (real cell, two mills or more), mill-2 cuts the cover under SMC II+ and its
// tooth 2 breaks 5 s into the job (smc-edge run --break-tooth), and an SMC I
// job for the bracket waits behind mill-1's. With channelNote: true (real
// cell), the catalog also has mill-9, no edge, whose wideband channel the
// cell warns hides the tool's chatter from module E.
//
// The real cell keeps its database and documents in `workDir`/cell: the
// caller's temporary folder, which the caller removes however the test ends
// (stopAll() stops the processes but knows nothing of folders).

import { execFileSync } from 'node:child_process';
import { mkdirSync, writeFileSync } from 'node:fs';
import { dirname, join, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';

import { Proc } from './processes.mjs';

const sourceDir = resolve(dirname(fileURLToPath(import.meta.url)), '..', '..');

function expand(template, vars) {
  return template.trim().split(/\s+/).map((a) => a.replace(/\{(\w+)\}/g, (_, k) => vars[k]));
}

async function fakeCell({ binDir, partition, mills }) {
  const p = new Proc('fake-mill', `${binDir}/smc-dashboard-fake-mill`,
    ['--mills', String(mills), '--partition', partition]);
  await p.waitFor(/^ready \d+ mills$/, 15000);
  return { kind: 'fake', procs: [p], log: p };
}

async function realCell({ binDir, partition, mills, breakage, channelNote, workDir }) {
  if (!workDir) throw new Error('startCell: a real cell needs workDir (a folder the caller removes)');
  const dir = join(workDir, 'cell');
  mkdirSync(dir);
  const db = join(dir, 'cell.db');
  execFileSync(`${binDir}/smc-cell`, ['db', 'init', '--db', db, '--seed'], { stdio: 'ignore' });
  const procs = [new Proc('smc-cell', `${binDir}/smc-cell`,
    ['serve', '--db', db, '--partition', partition])];
  for (let i = 1; i <= mills; i++) {
    const mill = `mill-${i}`;
    const extra = breakage && mill === 'mill-2' ? ['--break-tooth', '2@5'] : [];
    procs.push(new Proc(`smc-edge ${mill}`, `${binDir}/smc-edge`,
      ['run', '--machine', mill, '--partition', partition, '--paced', '--no-realtime',
       '--mill-model', join(sourceDir, 'cell/models/paper_face_mill.textproto'), ...extra]));
  }
  // mill-1 cuts the job-shop part under SMC II for the length of the test.
  const job = join(dir, 'job.textproto');
  writeFileSync(job, 'part_id: "housing-js"\nmachine_id: "mill-1"\n');
  execFileSync(`${binDir}/smc-cell`, ['job', 'submit', job, '--db', db], { stdio: 'ignore' });
  if (breakage && mills >= 2) {
    const cover = join(dir, 'cover.textproto');
    writeFileSync(cover, 'part_id: "cover-jsp"\nmachine_id: "mill-2"\n');
    execFileSync(`${binDir}/smc-cell`, ['job', 'submit', cover, '--db', db], { stdio: 'ignore' });
    // An SMC I job queued behind mill-1's: planned (its plan on the lobe
    // diagram), not cut during the test.
    const bracket = join(dir, 'bracket.textproto');
    writeFileSync(bracket, 'part_id: "bracket-tl"\nmachine_id: "mill-1"\n');
    execFileSync(`${binDir}/smc-cell`, ['job', 'submit', bracket, '--db', db], { stdio: 'ignore' });
  }
  if (channelNote) {
    // A machine with no edge running whose dynamometer samples the wideband
    // channel at 2 kHz through a fourth-order filter at 500 Hz, and a tap
    // test of it: the cell warns that the filter hides the tool's chatter.
    const doc = join(dir, 'mill-9.textproto');
    writeFileSync(doc, 'machines { id: "mill-9" name: "slow-channel mill" max_spindle_power_w: 745.7 ' +
      'max_feedrate_mm_s: 36 max_spindle_rpm: 3000 wideband { samples_per_tick: 1 cutoff_hz: 500 ' +
      'filter_order: 4 noise_rms_n: 2 } }\n' +
      'models { id: "mill-9.tap" machine_id: "mill-9" tool_id: "fm-r25-4t" material_id: "6061-T6" ' +
      `milling_file: "${join(sourceDir, 'cell/models/paper_face_mill.textproto')}" provenance: PROVENANCE_IDENTIFIED }\n`);
    execFileSync(`${binDir}/smc-cell`, ['catalog', 'apply', doc, '--db', db], { stdio: 'ignore' });
  }
  return { kind: 'real', procs, log: procs[0], db };
}

// Starts the cell and `mills` mills in `partition`; resolves once they run.
export async function startCell({ binDir, partition, workDir, mills = 2, kind: wanted,
  breakage = false, channelNote = false }) {
  const kind = wanted ?? process.env.SMC_TEST_CELL ?? 'real';
  const cell = kind === 'real' ? await realCell({ binDir, partition, mills, breakage, channelNote, workDir })
                               : await fakeCell({ binDir, partition, mills });
  cell.mills = Array.from({ length: mills }, (_, i) => `mill-${i + 1}`);
  return cell;
}
