// ctlgraph's HTML report: the click-a-block panel and the time plots.
// Written for this report (no library): the panels share one time view
// (zoom and pan move all), the cursor shows every signal's value at one
// instant, and each series is drawn from min/max per pixel column when it
// has more samples than pixels, so no peak disappears at any zoom.
(function () {
  "use strict";
  const meta = JSON.parse(document.getElementById("ctlgraph-meta").textContent);
  const bytes = (id) => {
    const s = atob(document.getElementById(id).textContent.trim());
    const b = new Uint8Array(s.length);
    for (let i = 0; i < s.length; i++) b[i] = s.charCodeAt(i);
    return b.buffer;
  };
  const t = new Float64Array(bytes("ctlgraph-t"));
  const all = new Float32Array(bytes("ctlgraph-y"));
  const n = t.length;
  // Column k of the trace (k >= 1; 0 is the time).
  const column = (k) => all.subarray((k - 1) * n, k * n);
  const PALETTE = ["#0072b2", "#d55e00", "#009e73", "#e69f00", "#56b4e9", "#cc79a7", "#000000", "#f0e442"];
  const full = [n ? t[0] : 0, n ? t[n - 1] : 1];
  if (!(full[1] > full[0])) full[1] = full[0] + 1;

  // ---- numbers -------------------------------------------------------
  function fmt(v) {
    if (!isFinite(v)) return String(v);
    const a = Math.abs(v);
    if (a !== 0 && (a < 1e-4 || a >= 1e6)) return v.toExponential(4);
    return String(Number(v.toPrecision(6)));
  }
  function ticks(lo, hi, count) {
    const span = hi - lo;
    if (!(span > 0) || !isFinite(span)) return [lo];
    const raw = span / count, mag = Math.pow(10, Math.floor(Math.log10(raw)));
    const step = [1, 2, 5, 10].map((m) => m * mag).find((s) => s >= raw) || 10 * mag;
    const out = [];
    for (let v = Math.ceil(lo / step) * step; v <= hi + step * 1e-9; v += step) out.push(Math.abs(v) < step * 1e-9 ? 0 : v);
    return out;
  }
  // First index with t[i] >= x.
  function lowerBound(x) {
    let lo = 0, hi = n;
    while (lo < hi) { const m = (lo + hi) >> 1; if (t[m] < x) lo = m + 1; else hi = m; }
    return lo;
  }
  // A signal's value at time x, linear between samples (as the checks read it).
  function valueAt(y, x) {
    const i = lowerBound(x);
    if (i <= 0) return y[0];
    if (i >= n) return y[n - 1];
    const a = t[i - 1], b = t[i];
    return b > a ? y[i - 1] + (y[i] - y[i - 1]) * (x - a) / (b - a) : y[i];
  }

  // ---- views ------------------------------------------------------------
  // Panels share one time view (zoom or pan one, all follow), except a
  // panel whose scope sets a window of its own: it keeps its own view.
  const panelsEl = document.getElementById("panels");
  const shared = full.slice();
  let cursor = null; // time under the mouse, or null
  const panels = [];
  function setView(p, a, b) {
    const v = p.view, min = (full[1] - full[0]) * 1e-9;
    if (!(b - a > min)) return;
    v[0] = Math.max(full[0], a);
    v[1] = Math.min(full[1], b);
    for (const q of panels) if (q.view === v) { q.box.dataset.t0 = v[0]; q.box.dataset.t1 = v[1]; }
    redraw();
  }
  let pending = false;
  function redraw() {
    if (pending) return;
    pending = true;
    requestAnimationFrame(() => { pending = false; panels.forEach(draw); });
  }

  // ---- one panel -------------------------------------------------------
  const M = { left: 72, right: 12, top: 10, bottom: 30 };
  function makePanel(spec, index) {
    const box = document.createElement("div");
    box.className = "panel";
    box.id = "panel-" + index;
    if (spec.title) {
      const h = document.createElement("h3");
      h.textContent = spec.title;
      box.appendChild(h);
    }
    const canvas = document.createElement("canvas");
    canvas.height = 240;
    box.appendChild(canvas);
    const legend = document.createElement("div");
    legend.className = "legend";
    box.appendChild(legend);
    panelsEl.appendChild(box);
    const own = spec.window && !(spec.window[0] === full[0] && spec.window[1] === full[1]);
    const p = { spec, box, canvas, legend, series: [], drag: null, view: own ? spec.window.slice() : shared };
    box.dataset.t0 = p.view[0];
    box.dataset.t1 = p.view[1];
    if (own) box.classList.add("own-view");
    spec.columns.forEach((k, j) => {
      const item = document.createElement("span");
      item.className = "item";
      item.dataset.signal = meta.headers[k];
      item.innerHTML = '<i style="background:' + PALETTE[j % PALETTE.length] + '"></i><b></b> <span class="value"></span>';
      item.querySelector("b").textContent = meta.headers[k];
      const s = { k, y: column(k), color: PALETTE[j % PALETTE.length], on: true, item };
      item.addEventListener("click", () => { s.on = !s.on; item.classList.toggle("off", !s.on); draw(p); });
      legend.appendChild(item);
      p.series.push(s);
    });
    attach(p);
    return p;
  }

  function yRange(p, i0, i1) {
    if (p.spec.y_limits) return p.spec.y_limits;
    let lo = Infinity, hi = -Infinity;
    for (const s of p.series) {
      if (!s.on) continue;
      for (let i = i0; i < i1; i++) { const v = s.y[i]; if (!isFinite(v)) continue; if (v < lo) lo = v; if (v > hi) hi = v; }
    }
    if (p.spec.band) { lo = Math.min(lo, p.spec.band[0]); hi = Math.max(hi, p.spec.band[1]); }
    if (!(hi >= lo) || !isFinite(lo) || !isFinite(hi)) return [-1, 1];
    const pad = hi > lo ? 0.06 * (hi - lo) : Math.max(Math.abs(lo), 1) * 0.1;
    return [lo - pad, hi + pad];
  }

  function draw(p) {
    const c = p.canvas, dpr = window.devicePixelRatio || 1;
    const W = c.clientWidth || 900, H = 240;
    if (c.width !== Math.round(W * dpr)) { c.width = Math.round(W * dpr); c.height = Math.round(H * dpr); }
    const g = c.getContext("2d");
    g.setTransform(dpr, 0, 0, dpr, 0, 0);
    g.clearRect(0, 0, W, H);
    const pw = W - M.left - M.right, ph = H - M.top - M.bottom;
    // The samples in view, and one each side so lines reach the edges.
    const i0 = Math.max(0, lowerBound(p.view[0]) - 1), i1 = Math.min(n, lowerBound(p.view[1]) + 1);
    const [ylo, yhi] = yRange(p, i0, i1);
    const X = (x) => M.left + (x - p.view[0]) / (p.view[1] - p.view[0]) * pw;
    const Y = (y) => M.top + (1 - (y - ylo) / (yhi - ylo)) * ph;
    p.X = X;
    p.plotWidth = pw;
    // Grid and axes.
    g.font = "11px sans-serif";
    g.strokeStyle = "#e4e4e4";
    g.fillStyle = "#333";
    g.lineWidth = 1;
    g.textAlign = "center";
    for (const x of ticks(p.view[0], p.view[1], Math.max(2, pw / 110))) {
      const px = Math.round(X(x)) + 0.5;
      g.beginPath(); g.moveTo(px, M.top); g.lineTo(px, M.top + ph); g.stroke();
      g.fillText(fmt(x), px, H - M.bottom + 14);
    }
    g.fillText("t [s]", M.left + pw / 2, H - 3);
    g.textAlign = "right";
    for (const y of ticks(ylo, yhi, 5)) {
      const py = Math.round(Y(y)) + 0.5;
      g.beginPath(); g.moveTo(M.left, py); g.lineTo(M.left + pw, py); g.stroke();
      g.fillText(fmt(y), M.left - 6, py + 4);
    }
    g.save();
    g.translate(12, M.top + ph / 2); g.rotate(-Math.PI / 2); g.textAlign = "center";
    g.fillText(p.spec.y_label || "", 0, 0);
    g.restore();
    g.strokeStyle = "#555";
    g.strokeRect(M.left + 0.5, M.top + 0.5, pw, ph);
    g.save();
    g.beginPath(); g.rect(M.left, M.top, pw, ph); g.clip();
    if (p.spec.band) {
      g.fillStyle = "rgba(60,160,60,0.12)";
      const a = Y(p.spec.band[1]), b = Y(p.spec.band[0]);
      g.fillRect(M.left, a, pw, b - a);
    }
    g.lineWidth = 1.5;
    for (const s of p.series) if (s.on) line(g, s.y, i0, i1, X, Y, pw, s.color);
    // The cursor, and the selection being dragged.
    if (cursor !== null && cursor >= p.view[0] && cursor <= p.view[1]) {
      g.strokeStyle = "#888"; g.lineWidth = 1;
      const px = Math.round(X(cursor)) + 0.5;
      g.beginPath(); g.moveTo(px, M.top); g.lineTo(px, M.top + ph); g.stroke();
    }
    if (p.drag && p.drag.mode === "zoom") {
      g.fillStyle = "rgba(0,114,178,0.12)";
      const a = Math.min(p.drag.x0, p.drag.x), b = Math.max(p.drag.x0, p.drag.x);
      g.fillRect(a, M.top, b - a, ph);
    }
    g.restore();
    for (const s of p.series) {
      s.item.querySelector(".value").textContent = cursor === null ? "" : "= " + fmt(valueAt(s.y, cursor));
    }
  }

  // A polyline through the samples; where there are more samples than
  // pixels, per pixel column its first, min, max and last value.
  function line(g, y, i0, i1, X, Y, pw, color) {
    g.strokeStyle = color;
    g.beginPath();
    let started = false;
    const to = (x, v) => { if (!isFinite(v)) { started = false; return; } if (started) g.lineTo(x, Y(v)); else { g.moveTo(x, Y(v)); started = true; } };
    if (i1 - i0 <= 2 * pw) {
      for (let i = i0; i < i1; i++) to(X(t[i]), y[i]);
    } else {
      let col = Math.floor(X(t[i0])), first = y[i0], last = first, lo = first, hi = first;
      const flush = () => { to(col, first); to(col, lo); to(col, hi); to(col, last); };
      for (let i = i0 + 1; i < i1; i++) {
        const c = Math.floor(X(t[i])), v = y[i];
        if (c !== col) { flush(); col = c; first = last = lo = hi = v; continue; }
        last = v; if (v < lo) lo = v; if (v > hi) hi = v;
      }
      flush();
    }
    g.stroke();
  }

  // ---- mouse -------------------------------------------------------------
  function timeAt(p, clientX) {
    const r = p.canvas.getBoundingClientRect();
    const x = clientX - r.left;
    return { x, time: p.view[0] + (x - M.left) / p.plotWidth * (p.view[1] - p.view[0]) };
  }
  function attach(p) {
    const c = p.canvas;
    c.addEventListener("mousedown", (e) => {
      const { x } = timeAt(p, e.clientX);
      p.drag = { mode: e.shiftKey ? "pan" : "zoom", x0: x, x, view0: p.view.slice() };
      e.preventDefault();
    });
    window.addEventListener("mousemove", (e) => {
      if (!p.drag) return;
      const { x } = timeAt(p, e.clientX);
      p.drag.x = x;
      if (p.drag.mode === "pan") {
        const dt = (x - p.drag.x0) / p.plotWidth * (p.drag.view0[1] - p.drag.view0[0]);
        let a = p.drag.view0[0] - dt, b = p.drag.view0[1] - dt;
        if (a < full[0]) { b += full[0] - a; a = full[0]; }
        if (b > full[1]) { a -= b - full[1]; b = full[1]; }
        setView(p, a, b);
      } else draw(p);
    });
    window.addEventListener("mouseup", () => {
      if (!p.drag) return;
      const d = p.drag;
      p.drag = null;
      if (d.mode === "zoom" && Math.abs(d.x - d.x0) > 3) {
        const span = d.view0[1] - d.view0[0];
        const a = d.view0[0] + (Math.min(d.x0, d.x) - M.left) / p.plotWidth * span;
        const b = d.view0[0] + (Math.max(d.x0, d.x) - M.left) / p.plotWidth * span;
        setView(p, a, b);
      } else draw(p);
    });
    c.addEventListener("mousemove", (e) => { cursor = timeAt(p, e.clientX).time; redraw(); });
    c.addEventListener("mouseleave", () => { cursor = null; redraw(); });
    c.addEventListener("dblclick", () => {
      const home = p.view === shared ? full : p.spec.window;
      setView(p, home[0], home[1]);
    });
    c.addEventListener("wheel", (e) => {
      e.preventDefault();
      const { time } = timeAt(p, e.clientX);
      const k = e.deltaY > 0 ? 1.25 : 0.8;
      setView(p, time - (time - p.view[0]) * k, time + (p.view[1] - time) * k);
    }, { passive: false });
  }

  // ---- the diagram ---------------------------------------------------
  const info = document.getElementById("block-info");
  function showBlock(name, g) {
    document.querySelectorAll("g.block.selected").forEach((e) => e.classList.remove("selected"));
    g.classList.add("selected");
    const b = meta.blocks[name] || { params: [], signals: [] };
    info.innerHTML = "";
    const h = document.createElement("h3");
    h.textContent = name;
    info.appendChild(h);
    const ty = document.createElement("p");
    ty.className = "type";
    ty.textContent = b.type || "";
    info.appendChild(ty);
    const table = document.createElement("table");
    table.className = "params";
    for (const [k, v] of b.params) {
      const row = table.insertRow();
      row.insertCell().textContent = k;
      row.insertCell().textContent = v;
    }
    if (b.params.length) info.appendChild(table);
    const sig = document.createElement("p");
    sig.className = "signals";
    if (!b.signals.length) sig.textContent = "Nothing of this block is recorded.";
    else {
      sig.textContent = "Recorded: ";
      b.signals.forEach((s, i) => {
        const a = document.createElement("a");
        a.href = "#";
        a.textContent = s;
        a.addEventListener("click", (e) => { e.preventDefault(); showSignal(s); });
        if (i) sig.appendChild(document.createTextNode(", "));
        sig.appendChild(a);
      });
    }
    info.appendChild(sig);
  }
  function showSignal(name) {
    const item = document.querySelector('.legend .item[data-signal="' + CSS.escape(name) + '"]');
    if (!item) return;
    const box = item.closest(".panel");
    box.scrollIntoView({ behavior: "smooth", block: "center" });
    box.classList.add("flash");
    setTimeout(() => box.classList.remove("flash"), 1200);
  }
  document.querySelectorAll("#diagram g.block").forEach((g) => {
    g.addEventListener("click", () => showBlock(g.dataset.name, g));
  });
  const expand = document.getElementById("expand");
  if (expand) {
    expand.addEventListener("change", () => {
      document.getElementById("diagram-collapsed").hidden = expand.checked;
      document.getElementById("diagram-expanded").hidden = !expand.checked;
    });
  }

  // ---- start ---------------------------------------------------------------
  meta.panels.forEach((spec, i) => panels.push(makePanel(spec, i)));
  panels.forEach(draw);
  window.addEventListener("resize", redraw);
  window.ctlgraphReport = { view: (k) => panels[k || 0].view.slice(), panels: panels.length };
  document.body.dataset.ready = String(performance.now());
})();
