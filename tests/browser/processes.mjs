// Child processes for the browser tests and benchmarks: spawned with their
// output captured line by line, waited on for a line with a deadline, and
// always stopped (SIGTERM, then SIGKILL) - also when the test fails.

import { spawn } from 'node:child_process';

const running = new Set();

export class Proc {
  constructor(name, cmd, args, env = {}) {
    this.name = name;
    this.lines = [];
    this.waiters = [];
    this.child = spawn(cmd, args, { stdio: ['ignore', 'pipe', 'pipe'], env: { ...process.env, ...env } });
    this.exited = new Promise((resolve) => this.child.on('exit', (code, sig) => {
      running.delete(this);
      this.exitCode = code ?? sig;
      resolve(this.exitCode);
    }));
    this.child.on('error', (e) => this.push(`[${name}] spawn error: ${e.message}`));
    running.add(this);
    for (const stream of [this.child.stdout, this.child.stderr]) {
      let rest = '';
      stream.setEncoding('utf8');
      stream.on('data', (chunk) => {
        rest += chunk;
        let nl;
        while ((nl = rest.indexOf('\n')) >= 0) {
          this.push(rest.slice(0, nl));
          rest = rest.slice(nl + 1);
        }
      });
    }
  }

  push(line) {
    this.lines.push(line);
    if (process.env.SMC_TEST_VERBOSE) console.log(`[${this.name}] ${line}`);
    for (const w of [...this.waiters]) {
      const m = line.match(w.re);
      if (m) {
        this.waiters.splice(this.waiters.indexOf(w), 1);
        clearTimeout(w.timer);
        w.resolve(m);
      }
    }
  }

  // Resolves with the match of the first line (already seen or coming)
  // matching `re`; rejects after `ms` or when the process exits first.
  waitFor(re, ms, since = 0) {
    for (let i = since; i < this.lines.length; i++) {
      const m = this.lines[i].match(re);
      if (m) return Promise.resolve(m);
    }
    return new Promise((resolve, reject) => {
      const w = { re, resolve };
      w.timer = setTimeout(() => {
        this.waiters.splice(this.waiters.indexOf(w), 1);
        reject(new Error(`${this.name}: no line matching ${re} within ${ms} ms; last lines:\n  ` +
          this.lines.slice(-12).join('\n  ')));
      }, ms);
      this.waiters.push(w);
      this.exited.then((code) => {
        if (!this.waiters.includes(w)) return;
        clearTimeout(w.timer);
        this.waiters.splice(this.waiters.indexOf(w), 1);
        reject(new Error(`${this.name} exited (${code}) before printing a line matching ${re}; last lines:\n  ` +
          this.lines.slice(-12).join('\n  ')));
      });
    });
  }

  async stop() {
    if (!running.has(this)) return this.exitCode;
    this.child.kill('SIGTERM');
    const timer = setTimeout(() => this.child.kill('SIGKILL'), 3000);
    const code = await this.exited;
    clearTimeout(timer);
    return code;
  }
}

// Stops every process still running (in a finally block, or on a signal).
export async function stopAll() {
  await Promise.all([...running].map((p) => p.stop()));
}

// Headless Chromium from Debian, driven over CDP by playwright-core.
export const CHROMIUM_ARGS = [
  '--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
  '--disable-background-networking', '--disable-component-update', '--disable-sync',
];
