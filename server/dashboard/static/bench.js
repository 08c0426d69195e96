// Test bench view: the paper's Table 2, the heat map of the 2-D error per grid cell (Fig. 13) and the
// truth-to-estimate scatter (Fig. 14) from GET /v1/samples/evaluation. Figures carry their own styles
// (attributes, not CSS classes) so the downloaded SVG files look as they do on the page.

import { getJson } from "./api.js";
import { byTestId, el, fmt, humanize, svgEl } from "./dom.js";

const CELL = /^\s*(-?\d+)\s*,\s*(-?\d+)\s*$/;
const RANGE = /^\s*(-?\d+)\s*(?:\.\.|:|,|to)\s*(-?\d+)\s*$/;
// 13 px: the scatter is drawn at 0.98 of its 600 px at most (the card's max-height), 12.8 px on screen
const FONT = "font-family:system-ui,sans-serif;font-size:13px;fill:#334";
// viridis, five stops: low error dark blue, high error yellow
const STOPS = [[68, 1, 84], [59, 82, 139], [33, 145, 140], [94, 201, 98], [253, 231, 37]];
const NO_FIX = "#c0392b";

export function colourAt(t) {
  const x = Math.min(Math.max(t, 0), 1) * (STOPS.length - 1);
  const i = Math.min(Math.floor(x), STOPS.length - 2);
  const mix = STOPS[i].map((v, k) => Math.round(v + (STOPS[i + 1][k] - v) * (x - i)));
  return `rgb(${mix.join(",")})`;
}

/** "a..b" (also "a:b", "a,b") as [low, high], or null when empty; throws a sentence when unreadable. */
export function parseRange(text, name) {
  if (!text.trim()) return null;
  const match = RANGE.exec(text);
  if (!match) throw new Error(`${name}: write it as low..high, e.g. -8..8 (got “${text}”)`);
  const [a, b] = [Number(match[1]), Number(match[2])];
  if (Math.abs(b - a) > 400) throw new Error(`${name}: at most 400 cells across (got ${text})`);
  return [Math.min(a, b), Math.max(a, b)];
}

/** The grid cell of an evaluation row: its 'i,j' label, else its truth rounded to the grid. */
function cellOf(row, cellM) {
  const match = CELL.exec(row.label || "");
  if (match) return [Number(match[1]), Number(match[2])];
  if (row.truth_m) return [Math.round(row.truth_m[0] / cellM), Math.round(row.truth_m[1] / cellM)];
  return null;
}

/** Rows grouped by cell "i,j": {i, j, errors: [mm...], refused: [reason...]}. */
function cellsOf(rows, cellM) {
  const cells = new Map();
  for (const row of rows) {
    const ij = cellOf(row, cellM);
    if (!ij) continue;
    const key = ij.join(",");
    if (!cells.has(key)) cells.set(key, { i: ij[0], j: ij[1], errors: [], refused: [] });
    const cell = cells.get(key);
    if (row.error_2d_mm != null) cell.errors.push(row.error_2d_mm);
    else if (!row.ok) cell.refused.push(row.reason || "no fix");
  }
  return cells;
}

/** A step of 1, 2 or 5 times a power of ten near `value`. */
function niceNumber(value) {
  const power = 10 ** Math.floor(Math.log10(value));
  return [1, 2, 5, 10].map((m) => m * power).find((n) => n >= value * 0.7) ?? 10 * power;
}

const mean = (values) => values.reduce((a, b) => a + b, 0) / values.length;

export class BenchView {
  constructor() {
    this.cellInput = byTestId("bench-cell-m");
    this.iInput = byTestId("bench-i-range");
    this.jInput = byTestId("bench-j-range");
    this.mapChoice = document.getElementById("bench-map-choice");
    this.evaluation = null;
    for (const input of [this.cellInput, this.mapChoice]) input.addEventListener("change", () => this.load());
    for (const input of [this.iInput, this.jInput]) {
      input.addEventListener("input", () => {
        input.dataset.typed = input.value.trim() ? "true" : ""; // emptied: back to the stored cells' span
        this.render();
      });
    }
    byTestId("bench-download").addEventListener("click", () => this.download());
  }

  async load() {
    const cellM = Number(this.cellInput.value);
    if (!(cellM > 0)) return this.failed(`Cell: a size in metres above 0 (got “${this.cellInput.value}”)`);
    const map = this.mapChoice.value ? `&map=${encodeURIComponent(this.mapChoice.value)}` : "";
    this.listMaps();
    try {
      this.evaluation = await getJson(`/v1/samples/evaluation?cell_m=${encodeURIComponent(cellM)}${map}`);
      this.cellM = cellM;
      this.render();
    } catch (error) {
      this.failed(`Could not evaluate the samples: ${error.message}`);
    }
  }

  /** The evaluation could not be had: its error, and no table or figures of an earlier one under it. */
  failed(message) {
    this.evaluation = null;
    document.getElementById("bench-body").hidden = true;
    document.getElementById("bench-empty").hidden = true;
    byTestId("bench-download").disabled = true;
    this.showError(message);
  }

  /** The samples are located again in the chosen map (the active one by default): a bench has its own map. */
  async listMaps() {
    const maps = await getJson("/v1/maps").catch(() => []);
    const chosen = this.mapChoice.value;
    this.mapChoice.replaceChildren(el("option", { value: "", text: "active map" }),
      ...maps.map((m) => el("option", { value: m.name, text: m.name })));
    this.mapChoice.value = maps.some((m) => m.name === chosen) ? chosen : "";
  }

  showError(message) {
    const node = document.getElementById("bench-error");
    node.hidden = !message;
    node.textContent = message || "";
  }

  render() {
    const evaluation = this.evaluation;
    if (!evaluation) return;
    const empty = evaluation.samples === 0;
    document.getElementById("bench-empty").hidden = !empty;
    document.getElementById("bench-body").hidden = empty;
    byTestId("bench-download").disabled = empty;
    if (empty) return;
    document.getElementById("bench-map").textContent = `map “${evaluation.map}”, cell ${this.cellM} m`;
    this.renderTable(evaluation);
    const cells = cellsOf(evaluation.rows, this.cellM);
    try {
      this.showError("");
      this.renderHeatmap(cells, this.plannedGrid(cells));
    } catch (error) {
      // an unreadable grid: no heat map of the previous one under its error (the table and scatter still hold)
      byTestId("bench-heatmap").replaceChildren();
      byTestId("bench-download").disabled = true;
      this.showError(error.message);
    }
    this.renderScatter(evaluation.rows);
  }

  renderTable(ev) {
    const head = ["Samples", "With truth", "Fixes", "Coverage", "Mean (mm)", "Std (mm)", "Min (mm)", "Max (mm)"];
    const values = [ev.samples, ev.with_truth, ev.fixes, `${(ev.coverage * 100).toFixed(1)} %`,
      fmt(ev.mean_mm, 2), fmt(ev.std_mm, 2), fmt(ev.min_mm, 2), fmt(ev.max_mm, 2)];
    const fields = ["samples", "with_truth", "fixes", "coverage", "mean_mm", "std_mm", "min_mm", "max_mm"];
    byTestId("bench-table").replaceChildren(
      el("thead", {}, el("tr", {}, head.map((h) => el("th", { class: "num", text: h })))),
      el("tbody", {}, el("tr", {}, values.map((v, k) => el("td", { class: "num", "data-field": fields[k], text: v })))),
    );
  }

  /** The planned grid: the typed i and j ranges, each the span of the stored cells until one is typed. */
  plannedGrid(cells) {
    const span = (values) => (values.length ? [Math.min(...values), Math.max(...values)] : [0, 0]);
    const range = (input, values, name) => {
      if (!input.dataset.typed) input.value = span(values).join("..");
      return parseRange(input.value, name) || span(values);
    };
    const iRange = range(this.iInput, [...cells.values()].map((c) => c.i), "i range");
    const jRange = range(this.jInput, [...cells.values()].map((c) => c.j), "j range");
    return { iRange, jRange };
  }

  renderHeatmap(cells, { iRange, jRange }) {
    const svg = byTestId("bench-heatmap");
    const [ni, nj] = [iRange[1] - iRange[0] + 1, jRange[1] - jRange[0] + 1];
    const size = Math.max(8, Math.min(40, Math.floor(520 / Math.max(ni, nj))));
    const [left, top] = [44, 16];
    const [gridW, gridH] = [ni * size, nj * size];
    const width = left + gridW + 130;
    const height = top + gridH + 44;
    const means = [...cells.values()].filter((c) => c.errors.length).map((c) => mean(c.errors));
    const maxMm = means.length ? Math.max(...means) : 1;
    const nodes = [svgEl("defs", {}, svgEl("pattern", { id: "hatch", width: 6, height: 6,
      patternUnits: "userSpaceOnUse", patternTransform: "rotate(45)" },
    svgEl("rect", { width: 6, height: 6, fill: "#f4f5f7" }),
    svgEl("line", { x1: 0, y1: 0, x2: 0, y2: 6, stroke: "#b8bec8", "stroke-width": 2 })))];
    nodes.push(svgEl("rect", { x: 0, y: 0, width, height, fill: "#fff" }));
    for (let i = iRange[0]; i <= iRange[1]; i++) {
      for (let j = jRange[0]; j <= jRange[1]; j++) {
        const x = left + (i - iRange[0]) * size;
        const y = top + (jRange[1] - j) * size; // j grows upward, as the map's Y
        nodes.push(this.cellRect(cells.get(`${i},${j}`), i, j, x, y, size, maxMm));
      }
    }
    nodes.push(...axisLabels(iRange, jRange, size, left, top, gridW, gridH));
    nodes.push(...colourBar(left + gridW + 18, top, Math.max(gridH, 120), maxMm));
    svg.setAttribute("viewBox", `0 0 ${width} ${Math.max(height, top + 170)}`);
    svg.setAttribute("width", width);
    svg.replaceChildren(...nodes);
  }

  cellRect(cell, i, j, x, y, size, maxMm) {
    const state = !cell ? "not-sampled" : cell.errors.length ? "sampled" : "no-fix";
    const errorMm = state === "sampled" ? mean(cell.errors) : null;
    const fill = { "not-sampled": "url(#hatch)", "no-fix": NO_FIX, sampled: colourAt(errorMm / maxMm) }[state];
    const title = state === "not-sampled" ? "not sampled" : state === "no-fix"
      ? `no fix (${cell.refused.map(humanize).join(", ")})`
      : `${errorMm.toFixed(2)} mm mean over ${cell.errors.length} sample(s)`;
    const rect = svgEl("rect", { "data-testid": "bench-cell", "data-cell": `${i},${j}`, "data-state": state,
      "data-error-mm": errorMm === null ? null : errorMm.toFixed(3), x, y, width: size, height: size, fill,
      stroke: "#fff", "stroke-width": 1 }, svgEl("title", { text: `cell ${i},${j}: ${title}` }));
    if (state !== "no-fix" || size < 12) return rect;
    const mark = svgEl("text", { x: x + size / 2, y: y + size / 2 + 4, "text-anchor": "middle",
      style: "font:bold 11px system-ui,sans-serif;fill:#fff;pointer-events:none", text: "✕" });
    return svgEl("g", {}, rect, mark);
  }

  renderScatter(rows) {
    const svg = byTestId("bench-scatter");
    const points = rows.filter((r) => r.truth_m && r.position_m && r.error_2d_mm != null);
    const refused = rows.filter((r) => r.truth_m && r.error_2d_mm == null);
    if (!points.length) {
      svg.setAttribute("viewBox", "0 0 400 60");
      svg.replaceChildren(svgEl("text", { x: 10, y: 34, style: FONT, text: "No fix with a known truth yet." }));
      return;
    }
    const proj = scatterProjection([...points, ...refused].map((r) => r.truth_m), this.cellM);
    const { px, py } = proj;
    const maxErrorM = Math.max(...points.map((r) => r.error_2d_mm)) / 1000;
    // magnify so the largest error is drawn about 40 px long
    const magnify = niceNumber(Math.max(40 / proj.scale / Math.max(maxErrorM, 1e-9), 1));
    const nodes = [svgEl("defs", {}, svgEl("marker", { id: "arrow", viewBox: "0 0 10 10", refX: 9, refY: 5,
      markerWidth: 6, markerHeight: 6, orient: "auto-start-reverse" },
    svgEl("path", { d: "M0,0 L10,5 L0,10 z", fill: "#e0632f" })))];
    nodes.push(svgEl("rect", { x: 0, y: 0, width: 600, height: 630, fill: "#fff" }), ...scatterAxes(proj));
    for (const row of points) {
      const [tx, ty] = row.truth_m;
      const [ex, ey] = [tx + (row.position_m[0] - tx) * magnify, ty + (row.position_m[1] - ty) * magnify];
      nodes.push(svgEl("g", { "data-testid": "bench-arrow", "data-id": row.id },
        svgEl("title", { text: `${row.label || row.id}: ${row.error_2d_mm.toFixed(2)} mm` }),
        svgEl("circle", { cx: px(tx), cy: py(ty), r: 3, fill: "#2f4a73" }),
        svgEl("line", { x1: px(tx), y1: py(ty), x2: px(ex), y2: py(ey), stroke: "#e0632f", "stroke-width": 1.6,
          "marker-end": "url(#arrow)" })));
    }
    for (const row of refused) {
      const [x, y] = [px(row.truth_m[0]), py(row.truth_m[1])];
      nodes.push(svgEl("path", { d: `M${x - 4},${y - 4}L${x + 4},${y + 4}M${x - 4},${y + 4}L${x + 4},${y - 4}`,
        stroke: NO_FIX, "stroke-width": 2 }, svgEl("title", { text: `${row.label || row.id}: no fix` })));
    }
    nodes.push(...scatterKey(magnify, proj.scale, maxErrorM, refused.length > 0));
    svg.setAttribute("viewBox", "0 0 600 630");
    svg.replaceChildren(...nodes);
  }

  /** One click: both figures as SVG files. */
  download() {
    const stamp = new Date().toISOString().slice(0, 19).replaceAll(":", "-");
    for (const [id, name] of [["bench-heatmap", "heatmap"], ["bench-scatter", "scatter"]]) {
      const svg = byTestId(id).cloneNode(true);
      svg.setAttribute("xmlns", "http://www.w3.org/2000/svg");
      const text = `<?xml version="1.0" encoding="UTF-8"?>\n${new XMLSerializer().serializeToString(svg)}`;
      const url = URL.createObjectURL(new Blob([text], { type: "image/svg+xml" }));
      const link = el("a", { href: url, download: `lumipose-bench-${name}-${stamp}.svg` });
      document.body.append(link);
      link.click();
      link.remove();
      setTimeout(() => URL.revokeObjectURL(url), 10000);
    }
  }
}

function axisLabels(iRange, jRange, size, left, top, gridW, gridH) {
  const nodes = [];
  const every = Math.ceil(18 / size);
  for (let i = iRange[0]; i <= iRange[1]; i += every) {
    nodes.push(svgEl("text", { x: left + (i - iRange[0] + 0.5) * size, y: top + gridH + 14, "text-anchor": "middle",
      style: FONT, text: i }));
  }
  for (let j = jRange[0]; j <= jRange[1]; j += every) {
    nodes.push(svgEl("text", { x: left - 6, y: top + (jRange[1] - j + 0.5) * size + 4, "text-anchor": "end",
      style: FONT, text: j }));
  }
  nodes.push(svgEl("text", { x: left + gridW / 2, y: top + gridH + 34, "text-anchor": "middle", style: FONT,
    text: "cell i (along X)" }));
  const jMiddle = Math.max(top + gridH / 2, 62); // a row or two is shorter than the label: it hangs below them
  nodes.push(svgEl("text", { x: 12, y: jMiddle, "text-anchor": "middle", style: FONT,
    transform: `rotate(-90 12 ${jMiddle})`, text: "cell j (along Y)" }));
  return nodes;
}

/** The colour bar in mm, and the keys of the two cells without a colour. */
function colourBar(x, top, height, maxMm) {
  const barH = height - 60;
  const nodes = [];
  const steps = 32;
  for (let k = 0; k < steps; k++) {
    nodes.push(svgEl("rect", { x, y: top + (barH * k) / steps, width: 14, height: barH / steps + 0.5,
      fill: colourAt(1 - k / steps) }));
  }
  for (const t of [0, 0.5, 1]) {
    nodes.push(svgEl("text", { x: x + 19, y: top + barH * (1 - t) + 4, style: FONT, text: (maxMm * t).toFixed(2) }));
  }
  nodes.push(svgEl("text", { x, y: top + barH + 20, style: FONT, text: "mm" })); // a line below the bar's "0.00"
  const key = (y, fill, label) => [svgEl("rect", { x, y, width: 14, height: 14, fill, stroke: "#ccd" }),
    svgEl("text", { x: x + 19, y: y + 11, style: FONT, text: label })];
  nodes.push(...key(top + barH + 28, NO_FIX, "no fix"), ...key(top + barH + 48, "url(#hatch)", "not sampled"));
  return nodes;
}

/** A square 520 px frame around the truths (metres), at least two cells across. */
function scatterProjection(truths, cellM) {
  const xs = truths.map((t) => t[0]);
  const ys = truths.map((t) => t[1]);
  const spanM = Math.max(Math.max(...xs) - Math.min(...xs), Math.max(...ys) - Math.min(...ys), cellM * 2);
  const marginM = spanM * 0.08 + cellM;
  const x0 = (Math.min(...xs) + Math.max(...xs)) / 2 - spanM / 2 - marginM;
  const y1 = (Math.min(...ys) + Math.max(...ys)) / 2 + spanM / 2 + marginM;
  const sideM = spanM + 2 * marginM;
  const scale = 520 / sideM;
  return { x0, x1: x0 + sideM, y0: y1 - sideM, y1, scale, px: (x) => 60 + (x - x0) * scale,
    py: (y) => 20 + (y1 - y) * scale };
}

/** The frame, light grid lines with their metres, and the axes' names. */
function scatterAxes(proj) {
  const step = niceNumber((proj.x1 - proj.x0) / 8);
  const nodes = [svgEl("rect", { x: 60, y: 20, width: 520, height: 520, fill: "none", stroke: "#d5d9e0" })];
  const label = (v) => String(+v.toFixed(3));
  for (let v = Math.ceil(proj.x0 / step) * step; v <= proj.x1; v += step) {
    nodes.push(svgEl("line", { x1: proj.px(v), x2: proj.px(v), y1: 20, y2: 540, stroke: "#eef0f4" }),
      svgEl("text", { x: proj.px(v), y: 556, "text-anchor": "middle", style: FONT, text: label(v) }));
  }
  for (let v = Math.ceil(proj.y0 / step) * step; v <= proj.y1; v += step) {
    nodes.push(svgEl("line", { x1: 60, x2: 580, y1: proj.py(v), y2: proj.py(v), stroke: "#eef0f4" }),
      svgEl("text", { x: 54, y: proj.py(v) + 4, "text-anchor": "end", style: FONT, text: label(v) }));
  }
  nodes.push(svgEl("text", { x: 320, y: 574, "text-anchor": "middle", style: FONT, text: "X (m)" }));
  return nodes;
}

/** The magnification's label and a reference arrow of a round error length. */
function scatterKey(magnify, scale, maxErrorM, withRefused) {
  const refMm = niceNumber(Math.max(maxErrorM * 1000 * 0.6, 1e-3));
  const length = (refMm / 1000) * magnify * scale;
  const y = 606;
  return [
    svgEl("line", { "data-testid": "bench-reference-arrow", x1: 64, y1: y, x2: 64 + length, y2: y, stroke: "#e0632f",
      "stroke-width": 1.6, "marker-end": "url(#arrow)" }),
    svgEl("text", { x: 72 + length, y: y + 4, style: FONT, text: `${refMm} mm error` }),
    svgEl("text", { "data-testid": "bench-magnification", x: 580, y: y + 4, "text-anchor": "end", style: FONT,
      text: `errors magnified ×${magnify} · dots: truth${withRefused ? " · ✕ no fix" : ""}` }),
  ];
}
