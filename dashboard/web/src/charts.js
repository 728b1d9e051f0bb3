// Live charts on uPlot (global `uPlot`, served from /vendor). Time is the
// mill's machine time in seconds (ForceSummary.machine_time_ns), never the
// browser's clock.

// Machine time in seconds -> axis label: h:mm:ss.s once past an hour
// (a monotonic clock counts from boot), else seconds.
export function formatMachineTime(t, decimals = 1) {
  if (t == null || !isFinite(t)) return '';
  if (Math.abs(t) < 3600) return t.toFixed(decimals);
  const day = ((t % 86400) + 86400) % 86400;
  const h = Math.floor(day / 3600);
  const m = Math.floor((day % 3600) / 60);
  const s = day % 60;
  return `${h}:${String(m).padStart(2, '0')}:${s.toFixed(decimals).padStart(decimals ? 3 + decimals : 2, '0')}`;
}

const css = (name) => getComputedStyle(document.documentElement).getPropertyValue(name).trim();

// Marks in the manner of the paper's Figures 6-8: feed-hold and suppression
// spans, pass boundaries, chatter events.
function marksPlugin(getMarks) {
  return {
    hooks: {
      drawClear: [(u) => {
        const m = getMarks();
        if (!m) return;
        const { ctx } = u;
        const { left, top, width, height } = u.bbox;
        const px = (t) => Math.round(u.valToPos(t, 'x', true));
        const [x0, x1] = [u.scales.x.min, u.scales.x.max];
        ctx.save();
        ctx.beginPath();
        ctx.rect(left, top, width, height);
        ctx.clip();
        for (const span of m.spans) {
          if (span.t1 < x0 || span.t0 > x1) continue;
          const a = px(Math.max(span.t0, x0));
          const b = px(Math.min(span.t1, x1));
          ctx.fillStyle = span.kind === 'hold' ? 'rgba(240,140,0,0.16)' : 'rgba(224,49,49,0.13)';
          ctx.fillRect(a, top, Math.max(b - a, 2), height);
          ctx.fillStyle = span.kind === 'hold' ? '#b35c00' : '#c92a2a';
          ctx.font = `${11 * devicePixelRatio}px system-ui, sans-serif`;
          ctx.fillText(span.kind === 'hold' ? 'feed hold' : 'suppression', a + 4, top + height - 6);
        }
        ctx.lineWidth = devicePixelRatio;
        ctx.font = `${11 * devicePixelRatio}px system-ui, sans-serif`;
        for (const p of m.passes) {
          if (p.t < x0 || p.t > x1) continue;
          const x = px(p.t);
          ctx.strokeStyle = '#868e96';
          ctx.setLineDash([4 * devicePixelRatio, 4 * devicePixelRatio]);
          ctx.beginPath();
          ctx.moveTo(x, top);
          ctx.lineTo(x, top + height);
          ctx.stroke();
          ctx.fillStyle = '#495057';
          ctx.fillText(p.label, x + 4, top + 14 * devicePixelRatio);
        }
        ctx.setLineDash([]);
        for (const c of m.chatter) {
          if (c.t < x0 || c.t > x1) continue;
          const x = px(c.t);
          ctx.strokeStyle = '#e03131';
          ctx.lineWidth = 2 * devicePixelRatio;
          ctx.beginPath();
          ctx.moveTo(x, top);
          ctx.lineTo(x, top + height);
          ctx.stroke();
          ctx.fillStyle = '#c92a2a';
          ctx.fillText(c.label, x + 4, top + 28 * devicePixelRatio);
        }
        ctx.restore();
      }],
    },
  };
}

function size(el, height) {
  return { width: Math.max(200, el.clientWidth), height };
}

// F_Y per revolution against the reference, with the commanded feed on a
// second axis and the marks.
export class ForceChart {
  constructor(el, getMarks, windowS = 30) {
    this.el = el;
    this.windowS = windowS;
    const opts = {
      ...size(el, 300),
      class: 'force-chart',
      legend: { live: true },
      cursor: { drag: { x: false, y: false } },
      scales: {
        x: { time: false, range: (u, min, max) => [Math.max(min, max - this.windowS), max] },
        y: { range: (u, min, max) => [0, Math.max(250, max * 1.12)] },
        feed: { range: (u, min, max) => [0, Math.max(20, max * 1.2)] },
      },
      axes: [
        { label: 'machine time', values: (u, ticks) => ticks.map((t) => formatMachineTime(t)),
          space: 70, stroke: css('--axis') },
        { label: 'force (N)', stroke: css('--axis'), grid: { stroke: css('--grid') } },
        { scale: 'feed', side: 1, label: 'feed (mm/s)', stroke: '#868e96', grid: { show: false } },
      ],
      series: [
        { label: 't (s)', value: (u, v) => formatMachineTime(v, 2) },
        { label: 'F_Y', stroke: '#1c7ed6', width: 1.6, value: (u, v) => (v == null ? '' : v.toFixed(0) + ' N') },
        { label: 'F_ref', stroke: '#e8590c', width: 1.6, dash: [7, 5],
          value: (u, v) => (v == null ? '' : v.toFixed(0) + ' N') },
        { label: 'feed', stroke: '#adb5bd', width: 1, scale: 'feed',
          value: (u, v) => (v == null ? '' : v.toFixed(1) + ' mm/s') },
      ],
      plugins: [marksPlugin(getMarks)],
    };
    this.u = new uPlot(opts, [[], [], [], []], el);
  }

  setData(cols) {
    this.u.setData(cols);
    // Without the pointer over the chart, the legend shows the newest values.
    if (this.u.cursor.left == null || this.u.cursor.left < 0) this.u.setLegend({ idx: cols[0].length - 1 });
  }
  resize() { this.u.setSize(size(this.el, 300)); }
  destroy() { this.u.destroy(); }
}

// Mean spindle power per revolution against the machine's limit (the
// configuration in force), on the same time axis as the force chart.
export class PowerChart {
  constructor(el, getMarks, windowS = 30) {
    this.el = el;
    this.windowS = windowS;
    const opts = {
      ...size(el, 170),
      class: 'power-chart',
      legend: { live: true },
      cursor: { drag: { x: false, y: false } },
      scales: {
        x: { time: false, range: (u, min, max) => [Math.max(min, max - this.windowS), max] },
        y: { range: (u, min, max) => [0, Math.max(1000, max * 1.12)] },
      },
      axes: [
        { label: 'machine time', values: (u, ticks) => ticks.map((t) => formatMachineTime(t)),
          space: 70, stroke: css('--axis') },
        { label: 'power (W)', stroke: css('--axis'), grid: { stroke: css('--grid') } },
      ],
      series: [
        { label: 't (s)', value: (u, v) => formatMachineTime(v, 2) },
        { label: 'spindle power', stroke: '#7048e8', width: 1.6,
          value: (u, v) => (v == null ? '' : v.toFixed(0) + ' W') },
        { label: 'limit', stroke: '#e03131', width: 1.2, dash: [7, 5],
          value: (u, v) => (v == null ? '' : v.toFixed(0) + ' W') },
      ],
      plugins: [marksPlugin(getMarks)],
    };
    this.u = new uPlot(opts, [[], [], []], el);
  }

  setData(cols) {
    this.u.setData(cols);
    if (this.u.cursor.left == null || this.u.cursor.left < 0) this.u.setLegend({ idx: cols[0].length - 1 });
  }
  resize() { this.u.setSize(size(this.el, 170)); }
  destroy() { this.u.destroy(); }
}

// Raw F_y and F_z of the last revolutions (ForceBatch).
export class RawChart {
  constructor(el) {
    this.el = el;
    const opts = {
      ...size(el, 190),
      class: 'raw-chart',
      legend: { live: false },
      cursor: { drag: { x: false, y: false } },
      scales: { x: { time: false } },
      axes: [
        { label: 'machine time', values: (u, ticks) => ticks.map((t) => formatMachineTime(t, 2)),
          space: 110, stroke: css('--axis') },
        { label: 'force (N)', stroke: css('--axis'), grid: { stroke: css('--grid') } },
      ],
      series: [
        {},
        { label: 'F_y', stroke: '#1c7ed6', width: 1 },
        { label: 'F_z', stroke: '#2f9e44', width: 1 },
      ],
    };
    this.u = new uPlot(opts, [[], [], []], el);
  }

  setBatches(batches) {
    const t = [];
    const fy = [];
    const fz = [];
    for (const b of batches) {
      for (let i = 0; i < b.f_y_n.length; i++) {
        t.push(b.t0 + i * b.dt);
        fy.push(b.f_y_n[i]);
        fz.push(b.f_z_n[i]);
      }
    }
    this.u.setData([t, fy, fz]);
  }
  resize() { this.u.setSize(size(this.el, 190)); }
  destroy() { this.u.destroy(); }
}

// A small F_Y / F_ref trace for the cell view.
export class Sparkline {
  constructor(el) {
    this.el = el;
    this.u = new uPlot({
      width: Math.max(160, el.clientWidth), height: 64,
      class: 'sparkline',
      legend: { show: false },
      cursor: { show: false },
      scales: { x: { time: false }, y: { range: (u, min, max) => [0, Math.max(250, max * 1.1)] } },
      axes: [{ show: false }, { show: false }],
      series: [{}, { stroke: '#1c7ed6', width: 1.2 }, { stroke: '#e8590c', width: 1, dash: [5, 4] }],
    }, [[], [], []], el);
  }
  setData(cols) { this.u.setData(cols); }
  destroy() { this.u.destroy(); }
}

// An SMC I plan on its lobe diagram: the critical depth against spindle
// speed (semi-discretization of the plan's structural model), the planned
// depth per pass at the planned speed, and the plan's own time-domain
// critical depth there.
export class LobeChart {
  constructor(el) {
    this.el = el;
    const dot = (color, size) => ({ paths: () => null, points: { show: true, size, stroke: color, fill: color } });
    const opts = {
      ...size(el, 260),
      class: 'lobe-chart',
      legend: { live: true },
      cursor: { drag: { x: false, y: false } },
      scales: { x: { time: false }, y: { range: (u, min, max) => [0, Math.max(1, max * 1.1)] } },
      axes: [
        { label: 'spindle speed (rpm)', stroke: css('--axis') },
        { label: 'depth of cut (mm)', stroke: css('--axis'), grid: { stroke: css('--grid') } },
      ],
      series: [
        { label: 'speed', value: (u, v) => (v == null ? '' : v.toFixed(0) + ' rpm') },
        { label: 'critical depth (lobes)', stroke: '#1c7ed6', width: 1.6, spanGaps: true,
          value: (u, v) => (v == null ? '' : v.toFixed(2) + ' mm') },
        { label: 'planned depth per pass', ...dot('#2f9e44', 10), value: (u, v) => (v == null ? '' : v.toFixed(2) + ' mm') },
        { label: 'critical depth (time domain, the plan\'s check)', ...dot('#e03131', 8),
          value: (u, v) => (v == null ? '' : v.toFixed(2) + ' mm') },
      ],
    };
    this.u = new uPlot(opts, [[], [], [], []], el);
  }
  setData(cols) { this.u.setData(cols); }
  resize() { this.u.setSize(size(this.el, 260)); }
  destroy() { this.u.destroy(); }
}
