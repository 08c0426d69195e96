// Small DOM and formatting helpers shared by the views.

const SVG_NS = "http://www.w3.org/2000/svg";

/** An HTML element with attributes and children (strings become text). */
export function el(tag, attrs = {}, ...children) {
  return fill(document.createElement(tag), attrs, children);
}

/** An SVG element with attributes and children. */
export function svgEl(tag, attrs = {}, ...children) {
  return fill(document.createElementNS(SVG_NS, tag), attrs, children);
}

function fill(node, attrs, children) {
  for (const [name, value] of Object.entries(attrs)) {
    if (value === undefined || value === null || value === false) continue;
    if (name === "text") node.textContent = value;
    else if (name.startsWith("on")) node.addEventListener(name.slice(2), value);
    else node.setAttribute(name, value === true ? "" : String(value));
  }
  for (const child of children.flat()) {
    if (child !== null && child !== undefined) node.append(child);
  }
  return node;
}

export const byTestId = (id, root = document) => root.querySelector(`[data-testid="${id}"]`);

/** A number with `digits` decimals, or an em dash when there is none. */
export function fmt(value, digits = 1, unit = "") {
  if (value === null || value === undefined || !Number.isFinite(value)) return "—";
  return `${value.toFixed(digits)}${unit ? " " + unit : ""}`;
}

export function fmtDuration(seconds) {
  const s = Math.max(0, Math.floor(seconds));
  const days = Math.floor(s / 86400);
  const hms = [Math.floor((s % 86400) / 3600), Math.floor((s % 3600) / 60), s % 60];
  const clock = hms.map((n) => String(n).padStart(2, "0")).join(":");
  return days ? `${days} d ${clock}` : clock;
}

export function fmtAgo(seconds) {
  if (seconds < 1) return "now";
  if (seconds < 90) return `${Math.round(seconds)} s ago`;
  if (seconds < 5400) return `${Math.round(seconds / 60)} min ago`;
  return `${Math.round(seconds / 3600)} h ago`;
}

/** Readable form of a machine reason: "beacon_cut_off" -> "beacon cut off". */
export const humanize = (reason) => String(reason).replaceAll("_", " ");

const scaledFigures = new WeakSet();

/** Sets `--px` on `svg`, its user units per CSS pixel, now and whenever it is drawn wider or narrower: a figure
 * scaled to its card would shrink its labels with it, so its CSS sizes them in screen pixels instead
 * (`font-size: max(11px, calc(13px * var(--px, 1)))`: 13 CSS px, larger only when the figure is). */
export function holdLabelSize(svg) {
  const update = () => {
    // the drawing's own scale, not the box's: a figure held by max-height is letterboxed inside its box
    const scale = svg.getBoundingClientRect().width > 0 ? svg.getScreenCTM()?.a : 0;
    if (scale > 0) svg.style.setProperty("--px", (1 / scale).toFixed(4));
  };
  if (!scaledFigures.has(svg)) {
    scaledFigures.add(svg);
    new ResizeObserver(update).observe(svg); // a hidden view's figure has no width until it is shown
  }
  update();
}
