// bvhlab's static site: draws each page's charts (inline SVG) and sortable tables from the JSON the page embeds.
// No network, no libraries: the pages open from file://.
"use strict";
(function () {
  const PALETTE = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f"];
  const SVG = "http://www.w3.org/2000/svg";
  const HEIGHT = 400;
  const MARGIN = { left: 78, right: 16, top: 12, bottom: 58 };
  // Table rows built before the load event; the others follow it.
  const FIRST_ROWS = 60;

  // A whole number as it is, any other with 4 significant digits (as the generator's `html::num`).
  function fmt(v) {
    if (v === null || v === undefined || !isFinite(v)) return "–";
    if (Number.isInteger(v) && Math.abs(v) < 1e15) return String(v);
    const m = Math.floor(Math.log10(Math.abs(v)));
    if (m < -3 || m >= 6) return v.toExponential(3).replace("e+", "e");
    return v.toFixed(Math.max(0, 3 - m));
  }

  // A tick label: as `fmt`, without trailing zeros.
  function tickLabel(v) {
    // Large whole numbers (instruction counts) read in thousands, millions, billions: 100M, not 100000000.
    const units = [[1e9, "G"], [1e6, "M"], [1e3, "k"]];
    for (const [u, suffix] of units) {
      if (Math.abs(v) >= 10 * u) return tickLabel(v / u) + suffix;
    }
    const text = fmt(v);
    return text.includes(".") && !text.includes("e") ? text.replace(/\.?0+$/, "") : text;
  }

  function svg(name, attrs, parent) {
    const e = document.createElementNS(SVG, name);
    for (const k in attrs) e.setAttribute(k, attrs[k]);
    if (parent) parent.appendChild(e);
    return e;
  }

  function html(name, attrs, parent, text) {
    const e = document.createElement(name);
    for (const k in attrs) e.setAttribute(k, attrs[k]);
    if (text !== undefined) e.textContent = text;
    if (parent) parent.appendChild(e);
    return e;
  }

  // Runs `f` once the page has loaded.
  function afterLoad(f) {
    if (document.readyState === "complete") setTimeout(f, 0);
    else window.addEventListener("load", () => setTimeout(f, 0), { once: true });
  }

  function embedded(id) {
    return JSON.parse(document.getElementById(id).textContent);
  }

  // Tooltip: one shared element, placed next to the pointer and kept inside the window.
  const tooltip = document.getElementById("tooltip");
  function place(ev) {
    const pad = 14;
    const r = tooltip.getBoundingClientRect();
    let x = ev.clientX + pad, y = ev.clientY + pad;
    if (x + r.width > window.innerWidth) x = ev.clientX - r.width - pad;
    if (y + r.height > window.innerHeight) y = ev.clientY - r.height - pad;
    tooltip.style.left = Math.max(0, x) + "px";
    tooltip.style.top = Math.max(0, y) + "px";
  }
  function showTip(ev, lines) {
    tooltip.textContent = lines.join("\n");
    tooltip.hidden = false;
    place(ev);
  }
  function hideTip() {
    tooltip.hidden = true;
  }

  // A scale from data to pixels: [lo, hi] (data, log10 of it when `log`) onto [a, b].
  function scale(lo, hi, log, a, b) {
    const t = (v) => (log ? Math.log10(v) : v);
    const [l, h] = [t(lo), t(hi)];
    const f = (v) => a + ((t(v) - l) / (h - l || 1)) * (b - a);
    f.lo = lo;
    f.hi = hi;
    f.log = log;
    return f;
  }

  // The extent of values (positive ones only on a log axis), padded.
  // `minSpan`: the least relative span the axis shows (e.g. 0.04: ±2% around the middle), so that a change of a
  // few parts per million is not drawn at full height.
  function extent(values, log, pad, minSpan) {
    let v = values.filter((x) => x !== null && isFinite(x) && (!log || x > 0));
    if (v.length === 0) v = log ? [1, 10] : [0, 1];
    let lo = Math.min(...v), hi = Math.max(...v);
    const mid = (lo + hi) / 2;
    if (minSpan && mid > 0 && hi - lo < minSpan * mid) {
      lo = mid * (1 - minSpan / 2);
      hi = mid * (1 + minSpan / 2);
    }
    if (log) {
      if (lo === hi) { lo /= 2; hi *= 2; }
      const f = Math.pow(hi / lo, pad);
      return [lo / f, hi * f];
    }
    if (lo === hi) { const d = Math.abs(lo) * 0.1 || 1; lo -= d; hi += d; }
    const d = (hi - lo) * pad;
    return [lo - d, hi + d];
  }

  // About `count` ticks at 1, 2 or 5 times a power of ten, never fewer than four (a finer step where they would be).
  function linearTicks(lo, hi, count) {
    const step0 = (hi - lo) / count;
    const p = Math.pow(10, Math.floor(Math.log10(step0)));
    const steps = [0.1, 0.2, 0.5, 1, 2, 5, 10].map((m) => m * p);
    let k = steps.findIndex((s) => s >= step0);
    if (k < 0) k = steps.length - 1;
    for (; ; k--) {
      const step = steps[k], ticks = [];
      for (let v = Math.ceil(lo / step) * step; v <= hi + step * 1e-9; v += step) ticks.push(Math.abs(v) < step * 1e-9 ? 0 : v);
      if (ticks.length >= 4 || k === 0) return ticks;
    }
  }

  // Ticks of an axis: a log axis labels 1, 2 and 5 of each decade over up to three decades (only the powers of ten
  // over more), every whole multiple where that leaves fewer than four, and linear steps within a narrow range.
  function ticksOf(s, count) {
    if (!s.log) return linearTicks(s.lo, s.hi, count);
    const decades = Math.log10(s.hi / s.lo);
    const choices = decades > 3 ? [[1], [1, 2, 5], [1, 2, 3, 4, 5, 6, 7, 8, 9]] : [[1, 2, 5], [1, 2, 3, 4, 5, 6, 7, 8, 9]];
    for (const mults of choices) {
      const ticks = [];
      for (let e = Math.floor(Math.log10(s.lo)); e <= Math.ceil(Math.log10(s.hi)); e++) {
        for (const m of mults) {
          const v = m * Math.pow(10, e);
          if (v >= s.lo * (1 - 1e-9) && v <= s.hi * (1 + 1e-9)) ticks.push(v);
        }
      }
      if (ticks.length >= 4) return ticks;
    }
    return linearTicks(s.lo, s.hi, count).filter((v) => v > 0);
  }

  // A series' colour: its own (by its label, the same in every chart of the page), else its style's.
  function colourOf(line) {
    return line.colour || PALETTE[line.style % PALETTE.length];
  }

  // A marker's outline centred on (x, y), as the PNG figures draw it (report/src/figures/chart.rs, `marker`).
  function markerPath(name, x, y) {
    const poly = (pts) => "M" + pts.map(([a, b]) => (x + a).toFixed(1) + " " + (y + b).toFixed(1)).join("L") + "Z";
    switch (name) {
      case "triangle": return poly([[0, -6], [6, 4.5], [-6, 4.5]]);
      case "square": return poly([[-4.5, -4.5], [4.5, -4.5], [4.5, 4.5], [-4.5, 4.5]]);
      case "diamond": return poly([[0, -6], [6, 0], [0, 6], [-6, 0]]);
      case "triangle-down": return poly([[0, 6], [6, -4.5], [-6, -4.5]]);
      case "cross": return poly([[-4.5, -6.5], [0, -2], [4.5, -6.5], [6.5, -4.5], [2, 0], [6.5, 4.5], [4.5, 6.5], [0, 2], [-4.5, 6.5], [-6.5, 4.5], [-2, 0], [-6.5, -4.5]]);
      case "plus": return poly([[-2, -6.5], [2, -6.5], [2, -2], [6.5, -2], [6.5, 2], [2, 2], [2, 6.5], [-2, 6.5], [-2, 2], [-6.5, 2], [-6.5, -2], [-2, -2]]);
      default: return `M${(x - 5).toFixed(1)} ${y.toFixed(1)}a5 5 0 1 0 10 0a5 5 0 1 0 -10 0Z`;
    }
  }

  // The order lines are drawn in, last on top (as the PNG figures): peers over ours, and within each the first in
  // legend order on top, so that a line overlapping another of its group (Embree under its packets) stays visible.
  function drawingOrder(lines) {
    const order = lines.map((_, i) => i).reverse();
    return order.filter((i) => !lines[i].front).concat(order.filter((i) => lines[i].front));
  }

  // One interactive chart in `figure`: title (wraps), log/linear buttons, the SVG plot, and the legend below it.
  function chart(figure, spec) {
    const state = { hidden: new Set(), logX: spec.log_x, logY: spec.log_y };
    html("figcaption", { class: "chart-title" }, figure, spec.title);
    const controls = html("div", { class: "controls" }, figure);
    const yButton = html("button", { type: "button", class: "axis-y" }, controls);
    yButton.addEventListener("click", () => { state.logY = !state.logY; draw(); });
    let xButton = null;
    if (spec.log_x) {
      xButton = html("button", { type: "button", class: "axis-x" }, controls);
      xButton.addEventListener("click", () => { state.logX = !state.logX; draw(); });
    }
    const plot = svg("svg", { class: "plot", role: "img", "aria-label": spec.title }, figure);
    const legend = html("ul", { class: "legend" }, figure);
    spec.lines.forEach((line, i) => {
      const li = html("li", {}, legend);
      const b = html("button", { type: "button", class: "series", "data-line": i, title: "show or hide" }, li);
      // The series' sample: its line (none on a category axis) and its marker, as drawn in the plot.
      const swatch = svg("svg", { class: "swatch", width: 26, height: 14, viewBox: "0 0 26 14" }, b);
      if (!spec.categorical) svg("line", { x1: 0, x2: 26, y1: 7, y2: 7, stroke: colourOf(line), "stroke-width": 2 }, swatch);
      svg("path", { class: "marker", d: markerPath(line.marker, 13, 7), fill: colourOf(line), "data-marker": line.marker }, swatch);
      html("span", {}, b, line.label);
      b.addEventListener("click", () => {
        if (state.hidden.has(i)) state.hidden.delete(i); else state.hidden.add(i);
        b.classList.toggle("off", state.hidden.has(i));
        draw();
      });
    });
    if (spec.guide) html("li", { class: "guide" }, legend, "- - " + spec.guide[1]);
    for (const m of spec.marks) {
      if (m.points.length) html("li", { class: "mark " + m.mark }, legend, (m.mark === "cross" ? "× " : "○ ") + m.label);
    }

    function draw() {
      yButton.textContent = "y: " + (state.logY ? "log" : "linear") + " (switch)";
      if (xButton) xButton.textContent = "x: " + (state.logX ? "log" : "linear") + " (switch)";
      plot.replaceChildren();
      const width = Math.max(320, figure.clientWidth);
      plot.setAttribute("width", width);
      plot.setAttribute("height", HEIGHT);
      plot.setAttribute("viewBox", `0 0 ${width} ${HEIGHT}`);
      const visible = spec.lines.filter((_, i) => !state.hidden.has(i));
      const xs = [], ys = [];
      for (const line of visible) for (const p of line.points) { xs.push(p.x); ys.push(p.y, p.lo, p.hi); }
      for (const m of spec.marks) for (const [x, y] of m.points) { xs.push(x); ys.push(y); }
      if (spec.guide) ys.push(spec.guide[0]);
      const ticked = spec.x_ticks.length > 0;
      if (ticked) for (const [x] of spec.x_ticks) xs.push(x);
      const [x0, x1] = ticked ? [Math.min(...xs) - 0.5, Math.max(...xs) + 0.5] : extent(xs, state.logX, 0.04);
      const [y0, y1] = extent(ys, state.logY, 0.06, spec.min_span);
      const top = MARGIN.top, bottom = HEIGHT - MARGIN.bottom;
      const Y = scale(y0, y1, state.logY, bottom, top);
      // The plot starts right of the widest y tick label and the y axis title beside it, so neither overlaps.
      const yTicks = ticksOf(Y, 6).map((t) => [t, tickLabel(t)]);
      const probe = svg("text", { class: "tick" }, plot);
      let widest = 0;
      for (const [, label] of yTicks) {
        probe.textContent = label;
        widest = Math.max(widest, probe.getComputedTextLength());
      }
      probe.remove();
      const left = Math.max(MARGIN.left, Math.ceil(widest) + 6 + 30), right = width - MARGIN.right;
      const X = scale(x0, x1, state.logX && !ticked, left, right);
      svg("rect", { class: "plot-area", x: left, y: top, width: right - left, height: bottom - top }, plot);

      // Axes: grid lines, tick labels and axis titles, all outside the plot area but inside the SVG.
      for (const [t, label] of yTicks) {
        const y = Y(t);
        svg("line", { class: "grid", x1: left, x2: right, y1: y, y2: y }, plot);
        svg("text", { class: "tick", x: left - 6, y: y + 4, "text-anchor": "end" }, plot).textContent = label;
      }
      const xTicks = ticked ? thin(spec.x_ticks, Math.max(2, Math.floor((right - left) / 64))) : ticksOf(X, 7).map((t) => [t, tickLabel(t)]);
      for (const [t, label] of xTicks) {
        const x = X(t);
        svg("line", { class: "grid", x1: x, x2: x, y1: top, y2: bottom }, plot);
        svg("text", { class: "tick", x, y: bottom + 16, "text-anchor": "middle" }, plot).textContent = label;
      }
      svg("text", { class: "axis-label", x: (left + right) / 2, y: HEIGHT - 12, "text-anchor": "middle" }, plot).textContent = spec.x_label;
      const yLabel = svg("text", { class: "axis-label", transform: `translate(16 ${(top + bottom) / 2}) rotate(-90)`, "text-anchor": "middle" }, plot);
      yLabel.textContent = spec.y_label;
      if (yLabel.getComputedTextLength() > bottom - top) {
        yLabel.setAttribute("textLength", bottom - top);
        yLabel.setAttribute("lengthAdjust", "spacingAndGlyphs");
      }

      const clip = "clip-" + figure.dataset.source;
      svg("rect", { x: left, y: top, width: right - left, height: bottom - top }, svg("clipPath", { id: clip }, plot));
      const layer = svg("g", { "clip-path": `url(#${clip})` }, plot);
      if (spec.guide) {
        const y = Y(spec.guide[0]);
        svg("line", { class: "guide", x1: left, x2: right, y1: y, y2: y }, layer);
      }
      for (const r of spec.rules) svg("line", { class: "rule", x1: X(r), x2: X(r), y1: top, y2: bottom }, layer);
      const ok = (v, s) => v !== null && isFinite(v) && (!s.log || v > 0);
      const order = drawingOrder(spec.lines);
      for (const i of order) {
        const line = spec.lines[i];
        if (state.hidden.has(i)) continue;
        const colour = colourOf(line);
        const pts = line.points.filter((p) => ok(p.x, X) && ok(p.y, Y));
        // A category axis (workloads, meshes) has nothing between its values: points with intervals, no line.
        if (pts.length > 1 && !spec.categorical) {
          const d = pts.map((p, k) => (k ? "L" : "M") + X(p.x).toFixed(1) + " " + Y(p.y).toFixed(1)).join("");
          svg("path", { class: "line", d, stroke: colour }, layer);
        }
        for (const p of pts) {
          if (ok(p.lo, Y) && ok(p.hi, Y) && p.lo !== p.hi) {
            const x = X(p.x);
            svg("line", { class: "bar", x1: x, x2: x, y1: Y(p.lo), y2: Y(p.hi), stroke: colour }, layer);
            if (spec.categorical) {
              for (const v of [p.lo, p.hi]) svg("line", { class: "bar", x1: x - 4, x2: x + 4, y1: Y(v), y2: Y(v), stroke: colour }, layer);
            }
          }
        }
      }
      for (const m of spec.marks) {
        for (const [x, y] of m.points) {
          if (!ok(x, X) || !ok(y, Y)) continue;
          if (m.mark === "ring") svg("circle", { class: "ring", cx: X(x), cy: Y(y), r: 8 }, layer);
          else svg("path", { class: "cross", d: `M${X(x) - 6} ${Y(y) - 6}l12 12m0 -12l-12 12` }, layer);
        }
      }
      // Points last, on top, each hoverable (and a link where it has one).
      for (const i of order) {
        const line = spec.lines[i];
        if (state.hidden.has(i)) continue;
        const colour = colourOf(line);
        line.points.forEach((p, k) => {
          if (!ok(p.x, X) || !ok(p.y, Y)) return;
          const parent = p.href ? svg("a", { href: p.href }, layer) : layer;
          svg("path", {
            class: "pt", d: markerPath(line.marker, X(p.x), Y(p.y)), fill: colour, "data-marker": line.marker,
            "data-line": i, "data-point": k, "data-series": line.label, "data-x": p.x,
          }, parent);
        });
      }
    }
    plot.addEventListener("mouseover", (ev) => {
      const t = ev.target;
      if (t.classList && t.classList.contains("pt")) showTip(ev, spec.lines[+t.dataset.line].points[+t.dataset.point].tip);
    });
    plot.addEventListener("mousemove", (ev) => { if (!tooltip.hidden) place(ev); });
    plot.addEventListener("mouseout", (ev) => { if (ev.target.classList && ev.target.classList.contains("pt")) hideTip(); });
    draw();
    return draw;
  }

  // Every k-th labelled tick, at most `most` of them.
  function thin(ticks, most) {
    const k = Math.ceil(ticks.length / most);
    return ticks.filter((_, i) => i % k === 0);
  }

  // A table sortable by clicking its headers (numbers as numbers); columns equal in every row listed above it.
  function table(div, data) {
    if (data.constant.length) {
      const p = html("p", { class: "constant" }, div, "Equal in every row: ");
      p.textContent += data.constant.map(([k, v]) => k + " = " + (typeof v === "number" ? fmt(v) : v)).join(" · ");
    }
    const wrap = html("div", { class: "table-wrap" }, div);
    const t = html("table", { class: "summary" }, wrap);
    const head = html("tr", {}, html("thead", {}, t));
    const body = html("tbody", {}, t);
    const state = { column: -1, sign: 1 };
    data.columns.forEach((c, i) => {
      const th = html("th", { class: c.numeric ? "num" : "", "data-column": i }, head, c.name);
      th.addEventListener("click", () => {
        state.sign = state.column === i ? -state.sign : 1;
        state.column = i;
        for (const h of head.children) h.removeAttribute("aria-sort");
        th.setAttribute("aria-sort", state.sign > 0 ? "ascending" : "descending");
        const rows = data.rows.slice();
        const key = (r) => r[i];
        rows.sort(c.numeric
          ? (a, b) => state.sign * ((key(a) ?? -Infinity) - (key(b) ?? -Infinity))
          : (a, b) => state.sign * String(key(a)).localeCompare(String(key(b)), undefined, { numeric: true }));
        fill(rows, rows.length);
      });
    });
    function build(rows) {
      const fragment = document.createDocumentFragment();
      for (const r of rows) {
        const tr = document.createElement("tr");
        for (let i = 0; i < r.length; i++) {
          const td = document.createElement("td");
          if (data.columns[i].numeric) { td.className = "num"; td.textContent = fmt(r[i]); } else td.textContent = r[i];
          tr.appendChild(td);
        }
        fragment.appendChild(tr);
      }
      return fragment;
    }
    // The first rows at once, the rest right after the page has loaded (a large table then never delays it).
    function fill(rows, now) {
      body.replaceChildren(build(rows.slice(0, now)));
      if (rows.length > now) afterLoad(() => body.appendChild(build(rows.slice(now))));
    }
    fill(data.rows, FIRST_ROWS);
  }

  const redraws = [];
  for (const figure of document.querySelectorAll("figure.chart")) redraws.push(chart(figure, embedded(figure.dataset.source)));
  for (const div of document.querySelectorAll("div.table")) table(div, embedded(div.dataset.source));
  let pending = 0;
  window.addEventListener("resize", () => {
    clearTimeout(pending);
    pending = setTimeout(() => redraws.forEach((f) => f()), 100);
  });
})();
