// Line charts and a heat map drawn as SVG: no chart library, nothing fetched. Exported figures are these SVGs.
"use strict";

const Charts = (() => {
  const NS = "http://www.w3.org/2000/svg";
  // Presentation attributes, not a <style> element or style="" (the page's Content-Security-Policy allows no
  // inline style, and an exported SVG must look the same on its own).
  const CLASSES = {
    text: {"font-family": "system-ui, sans-serif", "font-size": 11, fill: "#5b6775"},
    label: {"font-family": "system-ui, sans-serif", "font-size": 12, fill: "#1d2630"},
    grid: {stroke: "#e6e9ed"}, axis: {stroke: "#8a96a3"},
  };

  function el(name, attrs, parent) {
    const node = document.createElementNS(NS, name);
    const {class: kind, ...rest} = attrs || {};
    const base = kind ? CLASSES[kind] : name === "text" ? CLASSES.text : {};
    for (const [key, value] of Object.entries({...base, ...rest})) node.setAttribute(key, value);
    if (parent) parent.appendChild(node);
    return node;
  }

  // "Nice" ticks: 1, 2 or 5 times a power of ten, about `count` of them over [lo, hi].
  function ticks(lo, hi, count) {
    if (!(hi > lo)) { hi = lo + 1; }
    const raw = (hi - lo) / count, power = Math.pow(10, Math.floor(Math.log10(raw)));
    const step = [1, 2, 5, 10].map((m) => m * power).find((s) => s >= raw);
    const out = [];
    for (let v = Math.ceil(lo / step) * step; v <= hi + step * 1e-9; v += step) out.push(Math.abs(v) < step * 1e-9 ? 0 : v);
    return out;
  }

  function format(v) {
    const a = Math.abs(v);
    if (a !== 0 && (a >= 1e5 || a < 1e-3)) return v.toExponential(1).replace(".0e", "e").replace("e+", "e");  // 4e7, 2.5e7
    return String(Number(v.toPrecision(4)));
  }

  function frame(svg) {
    while (svg.firstChild) svg.removeChild(svg.firstChild);
    const box = svg.getBoundingClientRect();
    const width = Math.max(box.width, 320), height = Math.max(box.height, 180);
    svg.setAttribute("viewBox", `0 0 ${width} ${height}`);
    svg.setAttribute("xmlns", NS);
    el("rect", {x: 0, y: 0, width, height, fill: "#ffffff"}, svg);
    return {width, height, left: 56, right: 14, top: 12, bottom: 38};
  }

  // spec: {series: [{x: [], y: [], color, label, dash}], xLabel, yLabel, xMin, yMin, markers: [{x, label, color}],
  //        hLines: [y] (dashed reference lines), dots (draw points, not lines)}
  function line(svg, spec) {
    const f = frame(svg);
    const xs = spec.series.flatMap((s) => s.x), ys = spec.series.flatMap((s) => s.y).filter(Number.isFinite);
    if (!xs.length || !ys.length) { el("text", {x: f.width / 2, y: f.height / 2, "text-anchor": "middle"}, svg).textContent = spec.empty || "no data"; return; }
    let x0 = spec.xMin ?? Math.min(...xs), x1 = Math.max(...xs);
    let y0 = spec.yMin ?? Math.min(0, ...ys), y1 = Math.max(...ys);
    if (y1 === y0) y1 = y0 + 1;
    if (!(x1 > x0)) { x0 -= 0.5; x1 = x0 + 1; }  // one point: a unit span around it
    y1 += (y1 - y0) * 0.06;
    const W = f.width - f.left - f.right, H = f.height - f.top - f.bottom;
    const sx = (x) => f.left + (x - x0) / (x1 - x0) * W, sy = (y) => f.top + H - (y - y0) / (y1 - y0) * H;
    for (const t of ticks(y0, y1, 5)) {
      el("line", {x1: f.left, x2: f.left + W, y1: sy(t), y2: sy(t), class: "grid"}, svg);
      el("text", {x: f.left - 6, y: sy(t) + 4, "text-anchor": "end"}, svg).textContent = format(t);
    }
    for (const t of ticks(x0, x1, 6)) {
      el("line", {x1: sx(t), x2: sx(t), y1: f.top, y2: f.top + H, class: "grid"}, svg);
      el("text", {x: sx(t), y: f.top + H + 15, "text-anchor": "middle"}, svg).textContent = format(t);
    }
    el("line", {x1: f.left, x2: f.left + W, y1: f.top + H, y2: f.top + H, class: "axis"}, svg);
    el("line", {x1: f.left, x2: f.left, y1: f.top, y2: f.top + H, class: "axis"}, svg);
    el("text", {x: f.left + W / 2, y: f.height - 6, "text-anchor": "middle", class: "label"}, svg).textContent = spec.xLabel;
    el("text", {x: 14, y: f.top + H / 2, "text-anchor": "middle", class: "label", transform: `rotate(-90 14 ${f.top + H / 2})`}, svg).textContent = spec.yLabel;
    for (const y of spec.hLines || []) {  // horizontal reference lines (class thresholds)
      if (y >= y0 && y <= y1) el("line", {x1: f.left, x2: f.left + W, y1: sy(y), y2: sy(y), stroke: "#8a96a3", "stroke-dasharray": "4 3"}, svg);
    }
    for (const s of spec.series) {
      if (spec.dots) {  // points, not a line (one fruit each)
        s.x.forEach((x, i) => { if (Number.isFinite(s.y[i])) el("circle", {cx: sx(x).toFixed(1), cy: sy(s.y[i]).toFixed(1), r: 2.5, fill: s.color || "#2f6f4f"}, svg); });
        continue;
      }
      const d = s.x.map((x, i) => Number.isFinite(s.y[i]) ? `${i ? "L" : "M"}${sx(x).toFixed(1)},${sy(s.y[i]).toFixed(1)}` : "").join("");
      el("path", {d, fill: "none", stroke: s.color || "#2f6f4f", "stroke-width": 2, "stroke-dasharray": s.dash || "none"}, svg);
    }
    for (const m of spec.markers || []) {
      if (!(m.x >= x0 && m.x <= x1)) continue;
      el("line", {x1: sx(m.x), x2: sx(m.x), y1: f.top, y2: f.top + H, stroke: m.color || "#b3261e", "stroke-dasharray": "4 3"}, svg);
      el("text", {x: sx(m.x) + 4, y: f.top + 11, fill: m.color || "#b3261e"}, svg).textContent = m.label;
    }
    const legend = spec.series.filter((s) => s.label);
    legend.forEach((s, i) => {
      const y = f.top + 12 + 15 * i;
      el("line", {x1: f.left + W - 120, x2: f.left + W - 100, y1: y - 4, y2: y - 4, stroke: s.color, "stroke-width": 2}, svg);
      el("text", {x: f.left + W - 96, y}, svg).textContent = s.label;
    });
  }

  // A heat map: rows × columns of values (NaN/null blank), diverging at 0 (green below, red at and above).
  function heat(svg, spec) {
    const f = frame(svg);
    f.left = 64; f.bottom = 54; f.right = 74;  // the right margin holds the colour key
    const W = f.width - f.left - f.right, H = f.height - f.top - f.bottom;
    const cols = spec.columns.length, rows = spec.rows.length;
    const cw = W / cols, rh = H / rows;
    const color = (v) => {
      if (v === null || !Number.isFinite(v)) return "#f0f0f0";
      if (spec.share) {  // a share: pale green at 0 to red at 1
        const s = Math.max(0, Math.min(1, v));
        return `rgb(${230 + 10 * s | 0},${240 - 210 * s | 0},${230 - 200 * s | 0})`;
      }
      const t = Math.max(-1, Math.min(1, v));
      if (t >= 0) return `rgb(${200 + 40 * t | 0},${120 - 90 * t | 0},${110 - 80 * t | 0})`;
      return `rgb(${230 + 20 * t | 0},${240 + 5 * t | 0},${230 + 20 * t | 0})`;
    };
    spec.values.forEach((column, c) => column.forEach((v, r) => {
      el("rect", {x: f.left + c * cw, y: f.top + H - (r + 1) * rh, width: cw + 0.5, height: rh + 0.5, fill: color(v)}, svg)
        .appendChild(document.createElementNS(NS, "title")).textContent = `${spec.columns[c]}, ${spec.rows[r]}: ` + (spec.share ? `${v === null ? "–" : (100 * v).toFixed(1)} % bruised` : `margin ${v === null ? "–" : v.toFixed(2)}`);
    }));
    spec.columns.forEach((name, c) => {
      el("text", {x: f.left + (c + 0.5) * cw, y: f.top + H + 14, "text-anchor": "middle"}, svg).textContent = name;
      const safe = spec.safe[c];
      if (Number.isFinite(safe)) {
        const r = spec.position(safe);
        if (r >= 0 && r <= rows) el("line", {x1: f.left + c * cw + 2, x2: f.left + (c + 1) * cw - 2, y1: f.top + H - r * rh, y2: f.top + H - r * rh, stroke: "#1d2630", "stroke-width": 2}, svg);
      }
    });
    spec.rowTicks.forEach(([r, label]) => {
      el("text", {x: f.left - 6, y: f.top + H - r * rh + 4, "text-anchor": "end"}, svg).textContent = label;
    });
    // the colour key: what a cell's colour says (a share bruised from 0 to 1, or a margin from -1 to 1), in
    // steps drawn as rectangles so that an exported SVG or PNG carries it as drawn
    const key = el("g", {"data-part": "key"}, svg);  // (el's "class" is a preset style, not an attribute)
    const low = spec.share ? 0 : -1, steps = 40, kx = f.left + W + 16, kw = 12;
    for (let i = 0; i < steps; i += 1) {
      const v = low + (1 - low) * (i + 0.5) / steps;
      el("rect", {x: kx, y: f.top + H - (i + 1) * H / steps, width: kw, height: H / steps + 0.5, fill: color(v)}, key);
    }
    el("rect", {x: kx, y: f.top, width: kw, height: H, fill: "none", stroke: "#9aa3ad", "stroke-width": 0.5}, key);
    const marks = spec.share ? [[0, "0 %"], [0.5, "50 %"], [1, "100 %"]] : [[-1, "−1"], [0, "0"], [1, "1"]];
    for (const [v, label] of marks) {
      const y = f.top + H - (v - low) / (1 - low) * H;
      el("line", {x1: kx + kw, x2: kx + kw + 4, y1: y, y2: y, stroke: "#5b6672"}, key);
      el("text", {x: kx + kw + 6, y: y + 4, "text-anchor": "start"}, key).textContent = label;
    }
    el("text", {x: kx, y: f.top + H + 14, "text-anchor": "start"}, key).textContent =
      spec.share ? "bruised" : "margin";
    el("text", {x: f.left + W / 2, y: f.height - 8, "text-anchor": "middle", class: "label"}, svg).textContent = spec.xLabel;
    el("text", {x: 14, y: f.top + H / 2, "text-anchor": "middle", class: "label", transform: `rotate(-90 14 ${f.top + H / 2})`}, svg).textContent = spec.yLabel;
  }

  // Grouped bars over named categories.  spec: {categories: [], series: [{values: [], color, label}], yLabel,
  // xLabel, highlight: index of a category to mark (e.g. the worst transfer point), yMax, format(v) for labels}
  function bars(svg, spec) {
    const f = frame(svg);
    f.bottom = 52;
    const n = spec.categories.length, k = spec.series.length;
    const values = spec.series.flatMap((s) => s.values).filter(Number.isFinite);
    if (!n || !values.length) { el("text", {x: f.width / 2, y: f.height / 2, "text-anchor": "middle"}, svg).textContent = spec.empty || "no data"; return; }
    const W = f.width - f.left - f.right, H = f.height - f.top - f.bottom;
    let y1 = spec.yMax ?? Math.max(...values);
    if (!(y1 > 0)) y1 = 1;
    y1 *= spec.yMax ? 1 : 1.08;
    const sy = (y) => f.top + H - y / y1 * H;
    for (const t of ticks(0, y1, 5)) {
      el("line", {x1: f.left, x2: f.left + W, y1: sy(t), y2: sy(t), class: "grid"}, svg);
      el("text", {x: f.left - 6, y: sy(t) + 4, "text-anchor": "end"}, svg).textContent = (spec.tick || format)(t);
    }
    const slot = W / n, width = Math.min(46, slot * 0.8 / k);
    spec.categories.forEach((name, c) => {
      const middle = f.left + (c + 0.5) * slot;
      if (c === spec.highlight) el("rect", {x: f.left + c * slot + 1, y: f.top, width: slot - 2, height: H, fill: "#fbeceb"}, svg);
      spec.series.forEach((s, j) => {
        const v = s.values[c];
        if (!Number.isFinite(v)) return;
        const x = middle - k * width / 2 + j * width;
        el("rect", {x, y: sy(v), width: width - 2, height: Math.max(0, f.top + H - sy(v)), fill: s.color || "#2f6f4f"}, svg)
          .appendChild(document.createElementNS(NS, "title")).textContent = `${name}: ${s.label || ""} ${(spec.format || format)(v)}`;
      });
      // a long name on two lines, broken at the space nearest its middle (each line cut at 20 characters)
      const cut = (t) => t.length > 20 ? t.slice(0, 19) + "…" : t;
      let lines = [name];
      if (name.length > 16 && name.includes(" ")) {
        const spaces = [...name].map((ch, i) => ch === " " ? i : -1).filter((i) => i > 0);
        const at = spaces.reduce((best, i) => Math.abs(i - name.length / 2) < Math.abs(best - name.length / 2) ? i : best);
        lines = [name.slice(0, at), name.slice(at + 1)];
      }
      lines.forEach((text, j) => {
        el("text", {x: middle, y: f.top + H + 15 + 13 * j, "text-anchor": "middle", fill: c === spec.highlight ? "#b3261e" : "#5b6775"}, svg).textContent = cut(text);
      });
    });
    el("line", {x1: f.left, x2: f.left + W, y1: f.top + H, y2: f.top + H, class: "axis"}, svg);
    el("line", {x1: f.left, x2: f.left, y1: f.top, y2: f.top + H, class: "axis"}, svg);
    if (spec.xLabel) el("text", {x: f.left + W / 2, y: f.height - 6, "text-anchor": "middle", class: "label"}, svg).textContent = spec.xLabel;
    el("text", {x: 14, y: f.top + H / 2, "text-anchor": "middle", class: "label", transform: `rotate(-90 14 ${f.top + H / 2})`}, svg).textContent = spec.yLabel;
    spec.series.filter((s) => s.label).forEach((s, i) => {
      const y = f.top + 12 + 15 * i;
      el("rect", {x: f.left + W - 150, y: y - 9, width: 12, height: 10, fill: s.color || "#2f6f4f"}, svg);
      el("text", {x: f.left + W - 134, y}, svg).textContent = s.label;
    });
  }

  // A histogram: counts over bins [edges[i], edges[i+1]), with labelled vertical markers (class thresholds).
  // spec: {edges: [], counts: [], xLabel, yLabel, markers: [{x, label, color}], colors: [] per bin (optional)}
  function histogram(svg, spec) {
    const f = frame(svg);
    const edges = spec.edges, counts = spec.counts;
    if (!counts.length || !edges.length) { el("text", {x: f.width / 2, y: f.height / 2, "text-anchor": "middle"}, svg).textContent = spec.empty || "no data"; return; }
    const W = f.width - f.left - f.right, H = f.height - f.top - f.bottom;
    const x0 = edges[0], x1 = edges[edges.length - 1] > x0 ? edges[edges.length - 1] : x0 + 1;
    const y1 = Math.max(1, ...counts) * 1.08;
    const sx = (x) => f.left + (x - x0) / (x1 - x0) * W, sy = (y) => f.top + H - y / y1 * H;
    for (const t of ticks(0, y1, 5)) {
      if (t !== Math.round(t)) continue;
      el("line", {x1: f.left, x2: f.left + W, y1: sy(t), y2: sy(t), class: "grid"}, svg);
      el("text", {x: f.left - 6, y: sy(t) + 4, "text-anchor": "end"}, svg).textContent = format(t);
    }
    for (const t of ticks(x0, x1, 6)) el("text", {x: sx(t), y: f.top + H + 15, "text-anchor": "middle"}, svg).textContent = format(t);
    counts.forEach((count, i) => {
      if (!count) return;
      el("rect", {x: sx(edges[i]) + 0.5, y: sy(count), width: Math.max(1, sx(edges[i + 1]) - sx(edges[i]) - 1), height: f.top + H - sy(count),
                  fill: (spec.colors && spec.colors[i]) || "#2f6f4f"}, svg)
        .appendChild(document.createElementNS(NS, "title")).textContent = `${format(edges[i])} to ${format(edges[i + 1])}: ${count}`;
    });
    el("line", {x1: f.left, x2: f.left + W, y1: f.top + H, y2: f.top + H, class: "axis"}, svg);
    el("line", {x1: f.left, x2: f.left, y1: f.top, y2: f.top + H, class: "axis"}, svg);
    (spec.markers || []).forEach((m, i) => {  // labels staggered: two close thresholds stay readable
      if (!(m.x >= x0 && m.x <= x1)) return;
      el("line", {x1: sx(m.x), x2: sx(m.x), y1: f.top, y2: f.top + H, stroke: m.color || "#1d2630", "stroke-dasharray": "4 3"}, svg);
      el("text", {x: sx(m.x) + 4, y: f.top + 11 + 14 * (i % 3), fill: m.color || "#1d2630"}, svg).textContent = m.label;
    });
    el("text", {x: f.left + W / 2, y: f.height - 6, "text-anchor": "middle", class: "label"}, svg).textContent = spec.xLabel;
    el("text", {x: 14, y: f.top + H / 2, "text-anchor": "middle", class: "label", transform: `rotate(-90 14 ${f.top + H / 2})`}, svg).textContent = spec.yLabel;
  }

  function serialize(svg) {
    return new XMLSerializer().serializeToString(svg);
  }

  // A PNG of an SVG at twice its size, through a canvas (the SVG is self-contained: no outside resource).
  function png(svg) {
    const [, , width, height] = svg.getAttribute("viewBox").split(" ").map(Number);
    const image = new Image();
    const url = URL.createObjectURL(new Blob([serialize(svg)], {type: "image/svg+xml"}));
    return new Promise((resolve, reject) => {
      image.onload = () => {
        const canvas = document.createElement("canvas");
        canvas.width = width * 2; canvas.height = height * 2;
        const context = canvas.getContext("2d");
        context.scale(2, 2); context.drawImage(image, 0, 0);
        URL.revokeObjectURL(url);
        canvas.toBlob(resolve, "image/png");
      };
      image.onerror = reject;
      image.src = url;
    });
  }

  return {line, heat, bars, histogram, serialize, png};
})();
