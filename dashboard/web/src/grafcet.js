// Draws a mill's operation supervisor (a Grafcet, as the dashboard's
// /api/mills/ID/grafcet returns it) as SVG, and highlights the active steps,
// the enabled transitions and the active modules.
//
// Layout: steps are ranked by breadth-first distance from the initial steps,
// so every downward link spans exactly one rank; within a rank a step sits
// under its predecessors. Links that go up (back to an earlier step) run in
// a return lane on the right, one lane per target step, as Grafcets are
// usually drawn. Every element carries a data- attribute so tests can read
// the drawing (data-step="4" class="step active").

const SVG_NS = 'http://www.w3.org/2000/svg';
const STEP_W = 40;
const STEP_H = 36;
const RANK_H = 104;
const COL_W = 240;
const BRANCH_W = 96;
const CELL_W = 19;
const TOP = 22;
const LEFT = 34;

function el(name, attrs = {}, text) {
  const e = document.createElementNS(SVG_NS, name);
  for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
  if (text !== undefined) e.textContent = text;
  return e;
}

// Ranks and x positions of the steps.
export function layout(model) {
  const steps = model.steps;
  const byNumber = new Map(steps.map((s) => [s.number, s]));
  const next = new Map(steps.map((s) => [s.number, []]));
  for (const t of model.transitions) {
    for (const f of t.from) for (const g of t.to) next.get(f)?.push(g);
  }
  const rank = new Map();
  const queue = steps.filter((s) => s.initial).map((s) => s.number);
  if (queue.length === 0 && steps.length > 0) queue.push(steps[0].number);
  for (const n of queue) rank.set(n, 0);
  while (queue.length > 0) {
    const n = queue.shift();
    for (const m of next.get(n) ?? []) {
      if (!rank.has(m)) {
        rank.set(m, rank.get(n) + 1);
        queue.push(m);
      }
    }
  }
  let maxRank = Math.max(0, ...rank.values());
  for (const s of steps) if (!rank.has(s.number)) rank.set(s.number, ++maxRank);  // unreachable

  const x = new Map();
  const ranks = [];
  for (const s of steps) (ranks[rank.get(s.number)] ??= []).push(s.number);
  for (const row of ranks) {
    if (!row) continue;
    const want = (n) => {
      const parents = model.transitions
        .filter((t) => t.to.includes(n))
        .flatMap((t) => t.from)
        .filter((p) => x.has(p) && rank.get(p) === rank.get(n) - 1);
      return parents.length ? parents.reduce((a, p) => a + x.get(p), 0) / parents.length : 0;
    };
    const order = row.map((n) => ({ n, w: want(n) })).sort((a, b) => a.w - b.w || a.n - b.n);
    let prev = -Infinity;
    for (const { n, w } of order) {
      const pos = Math.max(w, prev + COL_W);
      x.set(n, pos);
      prev = pos;
    }
  }
  return { rank, x, byNumber };
}

export class GrafcetView {
  constructor(container) {
    this.container = container;
    this.model = null;
    this.svg = null;
  }

  setModel(model) {
    if (model === this.model && this.container.childElementCount > 0) return;
    if (model && this.model && JSON.stringify(model) === JSON.stringify(this.model)) return;
    this.model = model;
    this.container.replaceChildren();
    if (!model) {
      this.container.append(Object.assign(document.createElement('p'), {
        className: 'muted', textContent: 'No supervisor configuration received yet.' }));
      return;
    }
    if (!model.ok) {
      const pre = document.createElement('pre');
      pre.className = 'error';
      pre.textContent = 'The Grafcet of this configuration does not parse:\n' + model.errors.join('\n');
      this.container.append(pre);
      return;
    }
    this.svg = this.draw(model);
    this.container.append(this.svg);
  }

  draw(model) {
    const { rank, x } = layout(model);
    const top = (n) => TOP + rank.get(n) * RANK_H;
    let right = 0;
    for (const s of model.steps) {
      right = Math.max(right, x.get(s.number) + STEP_W / 2 + 10 + CELL_W * Math.max(4, s.actions.length));
    }
    const svg = el('svg', { class: 'grafcet', role: 'img',
      'aria-label': `Grafcet ${model.name}: ${model.title}` });
    const links = el('g', { class: 'links' });
    const nodes = el('g', { class: 'nodes' });
    svg.append(links, nodes);

    // Outgoing transitions per step: downward ones by target position, then
    // upward ones, those to the outer return lanes first (so that their
    // horizontal runs, lower down, cross nothing on their way out).
    const out = new Map(model.steps.map((s) => [s.number, []]));
    for (const t of model.transitions) out.get(t.from[0])?.push(t);
    const isUp = (t) => rank.get(t.to[0]) <= rank.get(t.from[0]);
    const upTargets = [...new Set(model.transitions.filter(isUp).map((t) => t.to[0]))]
      .sort((a, b) => rank.get(b) - rank.get(a) || x.get(a) - x.get(b));  // inner lanes: lower targets
    const laneX = new Map();
    let maxBranch = 0;
    const branchX = new Map();
    const labelW = (t) => 34 + 7.4 * `(${t.number}) ${t.receptivity}`.length;
    for (const s of model.steps) {
      const n = s.number;
      const ts = out.get(n);
      const down = ts.filter((t) => !isUp(t)).sort((a, b) => x.get(a.to[0]) - x.get(b.to[0]));
      const up = ts.filter(isUp).sort((a, b) => upTargets.indexOf(b.to[0]) - upTargets.indexOf(a.to[0]));
      out.set(n, [...down, ...up]);
      // The first branch leaves straight down; the others step right, past
      // the previous branch's label, each under its target when further right.
      let bx = null;
      let prev = null;
      for (const t of out.get(n)) {
        const under = isUp(t) ? -Infinity : x.get(t.to[0]);
        bx = bx === null ? x.get(n) : Math.max(bx + Math.max(BRANCH_W, labelW(prev)), under);
        branchX.set(t.number, bx);
        maxBranch = Math.max(maxBranch, bx + labelW(t));
        prev = t;
      }
    }
    right = Math.max(right, maxBranch);
    upTargets.forEach((n, i) => laneX.set(n, right + 18 + i * 16));
    const width = right + 28 + upTargets.length * 16;
    const height = TOP + (Math.max(...rank.values()) + 1) * RANK_H;

    const entryY = (n) => top(n) - 12;
    const path = (d, cls, attrs = {}) => links.append(el('path', { d, class: cls, ...attrs }));

    // Links into each step meet above it.
    for (const s of model.steps) {
      const n = s.number;
      const incoming = model.transitions.some((t) => t.to.includes(n));
      if (incoming) path(`M${x.get(n)},${entryY(n)} V${top(n)}`, 'link');
    }

    for (const s of model.steps) {
      const n = s.number;
      const ts = out.get(n);
      if (ts.length === 0) continue;
      const bottom = top(n) + STEP_H;
      const divY = bottom + 9;
      const barY = bottom + 24;
      const xs = ts.map((t) => branchX.get(t.number));
      path(`M${x.get(n)},${bottom} V${divY}`, 'link');
      if (ts.length > 1) path(`M${Math.min(...xs, x.get(n))},${divY} H${Math.max(...xs)}`, 'link');
      const ups = ts.filter(isUp).length;
      let upIndex = 0;
      for (const t of ts) {
        const bx = branchX.get(t.number);
        const target = t.to[0];
        const g = el('g', { class: 'transition', 'data-transition': t.number, 'data-from': n });
        links.append(g);
        const seg = (d, cls = 'link') => g.append(el('path', { d, class: cls }));
        seg(`M${bx},${divY} V${barY}`);
        if (!isUp(t)) {
          const midY = entryY(target);
          seg(`M${bx},${barY} V${midY} H${x.get(target)}`);
        } else {
          const lowY = barY + 14 + 9 * (ups - 1 - upIndex++);
          const lx = laneX.get(target);
          seg(`M${bx},${barY} V${lowY} H${lx} V${entryY(target)} H${x.get(target)}`);
          const ay = (lowY + entryY(target)) / 2;
          g.append(el('path', { d: `M${lx - 4},${ay + 5} L${lx},${ay - 3} L${lx + 4},${ay + 5} Z`,
            class: 'arrow' }));
        }
        g.append(el('line', { x1: bx - 11, x2: bx + 11, y1: barY, y2: barY, class: 'bar' }));
        g.append(el('text', { x: bx + 15, y: barY + 4, class: 'receptivity' },
          `(${t.number}) ${t.receptivity}`));
      }
    }

    for (const s of model.steps) {
      const n = s.number;
      const cx = x.get(n);
      const y = top(n);
      const g = el('g', { class: 'step', 'data-step': n });
      g.append(el('title', {}, `step ${n}: ${s.label}`));
      g.append(el('rect', { x: cx - STEP_W / 2, y, width: STEP_W, height: STEP_H, class: 'box' }));
      if (s.initial) {
        g.append(el('rect', { x: cx - STEP_W / 2 + 3.5, y: y + 3.5, width: STEP_W - 7,
          height: STEP_H - 7, class: 'inner' }));
      }
      g.append(el('text', { x: cx, y: y + STEP_H / 2 + 5, class: 'number' }, String(n)));
      g.append(el('circle', { cx: cx + STEP_W / 2 - 7, cy: y + STEP_H - 7, r: 3.2, class: 'token' }));
      const ax = cx + STEP_W / 2 + 10;
      g.append(el('text', { x: ax, y: y + 9, class: 'label' }, s.label));
      s.actions.forEach((a, i) => {
        const cell = el('g', { class: 'action', 'data-action': a.name, 'data-impulse': a.impulse });
        cell.append(el('rect', { x: ax + i * CELL_W, y: y + 14, width: CELL_W, height: 20 }));
        cell.append(el('text', { x: ax + i * CELL_W + CELL_W / 2, y: y + 28 },
          a.impulse ? a.name + '*' : a.name));
        const desc = model.actions.find((d) => d.name === a.name)?.description ?? '';
        cell.append(el('title', {}, `${a.impulse ? 'reset/initialise' : 'module'} ${a.name}: ${desc}`));
        g.append(cell);
      });
      nodes.append(g);
    }
    svg.setAttribute('viewBox', `${-LEFT} 0 ${width + LEFT} ${height}`);
    svg.setAttribute('width', width + LEFT);
    svg.setAttribute('height', height);
    return svg;
  }

  // activeSteps: step numbers; modules: letters of the active modules.
  update(activeSteps, modules) {
    if (!this.svg) return;
    const active = new Set(activeSteps ?? []);
    for (const g of this.svg.querySelectorAll('g.step')) {
      const n = Number(g.dataset.step);
      const on = active.has(n);
      g.classList.toggle('active', on);
      for (const a of g.querySelectorAll('g.action')) {
        a.classList.toggle('active', on && a.dataset.impulse === 'false' && modules.includes(a.dataset.action));
      }
    }
    for (const t of this.svg.querySelectorAll('g.transition')) {
      t.classList.toggle('enabled', active.has(Number(t.dataset.from)));
    }
  }
}
