// A beacon map drawn to scale in an SVG: map X to the right, Y up (the SVG's y is flipped).

import { holdLabelSize, svgEl } from "./dom.js";

const VIEW_WIDTH_PX = 1000;
const MIN_MARGIN_M = 0.4;

/** Outer size (width along the panel's x, height along its y) and corner radius of a beacon, metres. */
export function beaconExtent(beacon) {
  if (beacon.shape === "circle") return { w: beacon.diameter_m, h: beacon.diameter_m, r: beacon.diameter_m / 2 };
  const w = beacon.side_m ?? beacon.width_m;
  const h = beacon.side_m ?? beacon.height_m;
  return { w, h, r: beacon.corner_radius_m || 0 };
}

/** The map's bounding box around its panels and the given points [x, y], metres. */
function bounds(beacons, points) {
  const xs = [];
  const ys = [];
  for (const beacon of beacons) {
    const { w, h } = beaconExtent(beacon);
    const reach = Math.hypot(w, h) / 2 || 0; // an unreadable size (a preview) reaches nowhere
    xs.push(beacon.center_m[0] - reach, beacon.center_m[0] + reach);
    ys.push(beacon.center_m[1] - reach, beacon.center_m[1] + reach);
  }
  for (const [x, y] of points) {
    xs.push(x);
    ys.push(y);
  }
  return { x0: Math.min(...xs), x1: Math.max(...xs), y0: Math.min(...ys), y1: Math.max(...ys) };
}

/** Maps metres to SVG pixels for a box around `beacons` and `points`, with a margin. */
export function projectionFor(beacons, points = [], aspect = 0.62) {
  const box = bounds(beacons, points);
  const margin = Math.max(MIN_MARGIN_M, 0.15 * Math.max(box.x1 - box.x0, box.y1 - box.y0));
  let [x0, x1, y0, y1] = [box.x0 - margin, box.x1 + margin, box.y0 - margin, box.y1 + margin];
  // widen the short side so the drawing fills a VIEW_WIDTH_PX x (aspect * VIEW_WIDTH_PX) frame
  if ((y1 - y0) / (x1 - x0) < aspect) {
    const grow = ((x1 - x0) * aspect - (y1 - y0)) / 2;
    [y0, y1] = [y0 - grow, y1 + grow];
  } else {
    const grow = ((y1 - y0) / aspect - (x1 - x0)) / 2;
    [x0, x1] = [x0 - grow, x1 + grow];
  }
  const scale = VIEW_WIDTH_PX / (x1 - x0);
  return {
    x0, x1, y0, y1, scale,
    width: VIEW_WIDTH_PX,
    height: (y1 - y0) * scale,
    px: (x) => (x - x0) * scale,
    py: (y) => (y1 - y) * scale,
    contains: (x, y) => x > x0 && x < x1 && y > y0 && y < y1,
  };
}

/** Grid step (metres) that gives about 6-12 lines across `span` metres. */
function gridStep(span) {
  const steps = [0.01, 0.02, 0.05, 0.1, 0.2, 0.25, 0.5, 1, 2, 5, 10, 20, 50];
  return steps.find((step) => span / step <= 12) ?? 100;
}

function gridLayer(proj) {
  const step = gridStep(proj.x1 - proj.x0);
  const layer = svgEl("g", { class: "grid" });
  const label = (value) => String(+value.toFixed(3));
  for (let x = Math.ceil(proj.x0 / step) * step; x <= proj.x1; x += step) {
    const cls = Math.abs(x) < step / 1e3 ? "axis" : "";
    layer.append(svgEl("line", { x1: proj.px(x), x2: proj.px(x), y1: 0, y2: proj.height, class: cls }));
    layer.append(svgEl("text", { x: proj.px(x) + 3, y: proj.height - 5, class: "tick", text: label(x) }));
  }
  for (let y = Math.ceil(proj.y0 / step) * step; y <= proj.y1; y += step) {
    const cls = Math.abs(y) < step / 1e3 ? "axis" : "";
    layer.append(svgEl("line", { x1: 0, x2: proj.width, y1: proj.py(y), y2: proj.py(y), class: cls }));
    layer.append(svgEl("text", { x: 4, y: proj.py(y) - 4, class: "tick", text: label(y) }));
  }
  // a line above the X ticks and below the top edge, in ems: the labels' size follows the map's scale on screen
  layer.append(svgEl("text", { x: proj.width - 8, y: proj.height - 5, dy: "-1.3em", class: "axis-name",
    "text-anchor": "end", text: "X (m) →" }));
  layer.append(svgEl("text", { x: 8, y: 4, dy: "1em", class: "axis-name", text: "↑ Y (m)" }));
  return layer;
}

/** One panel: its outline to scale, turned by its yaw, and its ID. */
export function panelNode(beacon, proj, testId) {
  const { w, h, r } = beaconExtent(beacon);
  const [cx, cy] = [proj.px(beacon.center_m[0]), proj.py(beacon.center_m[1])];
  // a size the service would refuse (an upload's preview) is drawn as nothing rather than as an error
  const scaled = (metres) => (Number.isFinite(metres) && metres > 0 ? metres * proj.scale : 0);
  const size = { w: scaled(w), h: scaled(h), r: Math.min(scaled(r), scaled(w) / 2, scaled(h) / 2) };
  const idSize = Math.max(11, Math.min(22, size.h * 0.45));
  return svgEl("g", { "data-testid": testId, "data-beacon-id": beacon.id, class: "panel" },
    svgEl("title", { text: `beacon ${beacon.id}: ${(w * 1000).toFixed(0)} × ${(h * 1000).toFixed(0)} mm, ` +
      `yaw ${beacon.yaw_deg ?? 0}°, z ${beacon.center_m[2]} m` }),
    svgEl("rect", {
      x: cx - size.w / 2, y: cy - size.h / 2, width: size.w, height: size.h, rx: size.r, ry: size.r,
      // yaw turns counter-clockwise in the map; the flipped SVG turns the other way
      transform: `rotate(${-(beacon.yaw_deg ?? 0)} ${cx} ${cy})`,
    }),
    svgEl("text", { x: cx, y: cy + size.h / 2 + idSize + 2, "font-size": idSize, class: "panel-id",
      "text-anchor": "middle", text: beacon.id }),
  );
}

function scaleBar(proj) {
  const metres = gridStep(proj.x1 - proj.x0);
  const length = metres * proj.scale;
  const [x, y] = [proj.width - length - 20, 36]; // room for its label at 13 CSS px on a narrow map
  return svgEl("g", { class: "scalebar" },
    svgEl("line", { x1: x, x2: x + length, y1: y, y2: y }),
    svgEl("line", { x1: x, x2: x, y1: y - 5, y2: y + 5 }),
    svgEl("line", { x1: x + length, x2: x + length, y1: y - 5, y2: y + 5 }),
    svgEl("text", { x: x + length / 2, y: y - 8, "text-anchor": "middle",
      text: metres >= 1 ? `${metres} m` : `${Math.round(metres * 1000)} mm` }),
  );
}

/** Draws `beaconMap` into `svg` (cleared) and returns the projection; later layers go on top.
 * `panelTestId` tells the live room's panels ("panel") from another drawing's ("map-panel"). */
export function drawRoom(svg, beaconMap, points = [], panelTestId = "panel") {
  const proj = projectionFor(beaconMap.beacons, points);
  svg.replaceChildren();
  svg.setAttribute("viewBox", `0 0 ${proj.width} ${proj.height.toFixed(1)}`);
  holdLabelSize(svg);
  const panels = beaconMap.beacons.map((beacon) => panelNode(beacon, proj, panelTestId));
  svg.append(gridLayer(proj), svgEl("g", { class: "panels" }, panels), scaleBar(proj));
  return proj;
}
