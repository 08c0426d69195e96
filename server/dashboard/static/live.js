// Live view: the active map to scale, each device's marker, 2-sigma ellipse and fading track, and a table.

import { byTestId, el, fmt, fmtAgo, humanize, svgEl } from "./dom.js";
import { drawRoom } from "./roommap.js";

const PALETTE = ["#2f7fe0", "#e0632f", "#1f9d6b", "#a34fd6", "#d6a21f", "#d63f7a", "#3fb6c9", "#7a8a2f"];
const FADE_SEGMENTS = 24;
const IDLE_S = 30; // a device not seen for this long is drawn faded, without its name (its title has it)
const MAX_TRACK = 200; // points of a track kept, as the service keeps
const MAX_ROWS = 50; // devices listed in the table, most recently seen first

/** Two-sigma ellipse of a 2x2 covariance [[a, b], [b, c]] (m^2): radii (m) and the major axis' angle (deg). */
export function ellipse2Sigma(cov) {
  const [a, b, c] = [cov[0][0], cov[0][1], cov[1][1]];
  const mean = (a + c) / 2;
  const spread = Math.hypot((a - c) / 2, b);
  const angle = 0.5 * Math.atan2(2 * b, a - c);
  return { major: 2 * Math.sqrt(Math.max(mean + spread, 0)), minor: 2 * Math.sqrt(Math.max(mean - spread, 0)),
    angleDeg: (angle * 180) / Math.PI };
}

const colours = new Map(); // device -> colour, in the order devices are first seen: neighbours differ

function colourOf(name) {
  if (!colours.has(name)) colours.set(name, PALETTE[colours.size % PALETTE.length]);
  return colours.get(name);
}

/** Where a device is: its last filtered position (the track's newest point), else its last raw fix. */
function devicePosition(device) {
  const newest = device.track?.at(-1);
  if (newest) return [newest[1], newest[2]];
  return device.last?.position_m ? device.last.position_m.slice(0, 2) : null;
}

export class LiveView {
  constructor({ openFrame }) {
    this.svg = byTestId("room-map");
    this.tbody = byTestId("device-table").querySelector("tbody");
    this.openFrame = openFrame;
    this.devices = new Map();
    this.map = null;
    this.proj = null;
    this.clockOffsetS = 0;
    this.windowS = 10; // the window of fix_rate_hz and refused, from the latest LiveDevices
    this.rows = new Map(); // device -> {key, row}: a row is built again only when what it shows changed
  }

  /** The server's clock now, as the latest event or status set it (seconds). */
  serverNowS() {
    return Date.now() / 1000 + this.clockOffsetS;
  }

  /** Located in the drawn map (a device in another map is listed, not drawn on this room). */
  inDrawnMap(device) {
    return device.map === this.map?.name;
  }

  /** A status event (every 2 s): set the clock again and let the rates of quiet devices run out. */
  onStatus(status) {
    this.clockOffsetS = status.started_s + status.uptime_s - Date.now() / 1000;
    this.renderTable();
  }

  setMap(beaconMap) {
    this.map = beaconMap;
    this.proj = null;
    this.render();
  }

  /** Replaces every device (the initial GET) or merges the changed ones (an SSE `devices` event). */
  update(liveDevices, replace = false) {
    this.clockOffsetS = liveDevices.time_s - Date.now() / 1000;
    if (replace) this.devices.clear();
    for (const device of liveDevices.devices) this.devices.set(device.device, this.merged(device));
    if (liveDevices.window_s) {
      this.windowS = liveDevices.window_s;
      document.getElementById("refused-head").textContent = `Refused (${Math.round(liveDevices.window_s)} s)`;
    }
    this.render();
  }

  /** An event's device carries only its track's new points: append them to those already drawn. */
  merged(device) {
    const known = this.devices.get(device.device)?.track || [];
    const newestS = known.length ? known.at(-1)[0] : -Infinity;
    const track = known.concat((device.track || []).filter((point) => point[0] > newestS)).slice(-MAX_TRACK);
    return { ...device, track };
  }

  deviceNames() {
    return [...this.devices.values()].sort((a, b) => b.last_seen_s - a.last_seen_s).map((d) => d.device);
  }

  render() {
    this.renderMap();
    this.renderTable();
    const count = this.devices.size;
    const elsewhere = [...this.devices.values()].filter((d) => !this.inDrawnMap(d)).length;
    document.getElementById("live-empty").hidden = count > 0;
    document.getElementById("live-summary").textContent = this.map
      ? `Map “${this.map.name}”: ${this.map.beacons.length} panels · ${count} device${count === 1 ? "" : "s"}` +
        (elsewhere ? ` (${elsewhere} in other maps, not drawn)` : "")
      : "Loading the active map…";
  }

  trackPoints() {
    return [...this.devices.values()].filter((d) => this.inDrawnMap(d))
      .flatMap((d) => (d.track || []).map((p) => [p[1], p[2]]));
  }

  renderMap() {
    if (!this.map) return;
    const points = this.trackPoints();
    // redraw the room only when a device walks out of the drawn area
    if (!this.proj || points.some(([x, y]) => !this.proj.contains(x, y))) {
      this.proj = drawRoom(this.svg, this.map, points);
      this.layer = svgEl("g", { class: "devices" });
      this.svg.append(this.layer);
      document.getElementById("map-scale").textContent = `${(this.proj.x1 - this.proj.x0).toFixed(2)} m across`;
    }
    const nowS = this.serverNowS();
    // idle devices first, so the active ones are drawn over them
    const devices = [...this.devices.values()].filter((d) => this.inDrawnMap(d))
      .sort((a, b) => a.last_seen_s - b.last_seen_s);
    this.layer.replaceChildren(...devices.map((d) => this.deviceNode(d, nowS)).filter(Boolean));
  }

  deviceNode(device, nowS) {
    const at = devicePosition(device);
    if (!at) return null;
    const { px, py, scale } = this.proj;
    const colour = colourOf(device.device);
    const idle = nowS - device.last_seen_s > IDLE_S;
    const refused = !device.last?.ok;
    const group = svgEl("g", {
      "data-testid": "device-marker", "data-device": device.device, "data-x": at[0], "data-y": at[1],
      class: `device${idle ? " idle" : ""}${refused ? " refused" : ""}`, style: `--c:${colour}`,
      tabindex: 0, role: "link",
      onclick: () => this.openFrame(device.device),
      onkeydown: (event) => event.key === "Enter" && this.openFrame(device.device),
    });
    const title = svgEl("title", { text: `${device.device}: (${at[0].toFixed(3)}, ${at[1].toFixed(3)}) m` });
    group.append(title, ...this.trackNodes(device.track || []));
    const cov = device.last?.ok ? device.last.position_covariance_m2 : null;
    if (cov) {
      const e = ellipse2Sigma(cov);
      // drawn to scale: millimetres are a pixel or two on a room's map, so the title says how large
      title.textContent += `, 2σ ellipse ${(e.major * 1000).toFixed(1)} × ${(e.minor * 1000).toFixed(1)} mm`;
      group.append(svgEl("ellipse", {
        "data-testid": "device-ellipse", class: "ellipse", cx: px(at[0]), cy: py(at[1]),
        rx: Math.max(e.major * scale, 0.5), ry: Math.max(e.minor * scale, 0.5),
        transform: `rotate(${-e.angleDeg} ${px(at[0])} ${py(at[1])})`,
        "data-major-m": e.major.toPrecision(3), "data-minor-m": e.minor.toPrecision(3),
      }));
    }
    group.append(svgEl("circle", { class: "marker", cx: px(at[0]), cy: py(at[1]), r: 7 }));
    if (!idle) {
      group.append(svgEl("text", { class: "device-label", x: px(at[0]) + 11, y: py(at[1]) - 9, text: device.device }));
    }
    return group;
  }

  /** The whole track as one faint polyline, and its newest part in segments that fade with age. */
  trackNodes(track) {
    if (track.length < 2) return [];
    const { px, py } = this.proj;
    const xy = track.map((p) => `${px(p[1]).toFixed(1)},${py(p[2]).toFixed(1)}`);
    const nodes = [svgEl("polyline", { "data-testid": "device-track", class: "track", points: xy.join(" ") })];
    const first = Math.max(0, xy.length - 1 - FADE_SEGMENTS * 4);
    const chunk = Math.max(1, Math.ceil((xy.length - 1 - first) / FADE_SEGMENTS));
    for (let start = first; start < xy.length - 1; start += chunk) {
      const age = (xy.length - 1 - start) / (xy.length - first);
      nodes.push(svgEl("polyline", { class: "track-fade", "stroke-opacity": (0.9 * (1 - age)).toFixed(2),
        points: xy.slice(start, start + chunk + 1).join(" ") }));
    }
    return nodes;
  }

  renderTable() {
    const nowS = this.serverNowS();
    const names = this.deviceNames();
    const shown = names.slice(0, MAX_ROWS).map((name) => [name, this.cachedRow(this.devices.get(name), nowS)]);
    this.rows = new Map(shown);
    const rows = shown.map(([, cached]) => cached.row);
    const more = names.length - shown.length;
    if (more > 0) {
      rows.push(el("tr", { "data-testid": "device-more", class: "more" },
        el("td", { colspan: 6, class: "muted", text: `and ${more} more device${more === 1 ? "" : "s"}` })));
    }
    this.tbody.replaceChildren(...rows);
  }

  cachedRow(device, nowS) {
    const values = this.rowValues(device, nowS);
    const key = JSON.stringify(values);
    const cached = this.rows.get(device.device);
    return cached?.key === key ? cached : { key, row: this.deviceRow(values) };
  }

  /** What a device's row shows, as text. Its rates are of the last window_s: none once it is quiet longer. */
  rowValues(device, nowS) {
    const last = device.last || {};
    const quiet = nowS - device.last_seen_s > this.windowS;
    const sigma = last.position_sigma_m ? Math.hypot(last.position_sigma_m[0], last.position_sigma_m[1]) : null;
    return {
      device: device.device,
      note: `${device.fixes}/${device.frames} fixes` + (sigma === null ? "" : ` · σ ${(sigma * 1000).toFixed(1)} mm`),
      otherMap: this.map && !this.inDrawnMap(device) ? device.map : null,
      beacon: last.ok ? `${last.beacon_id ?? "—"}` : "—",
      beaconSource: last.ok && last.beacon_id_source ? humanize(last.beacon_id_source) : null,
      rate: fmt(quiet ? 0 : device.fix_rate_hz, 1, "Hz"),
      refused: quiet ? [] : Object.entries(device.refused || {}).filter(([, share]) => share > 0)
        .map(([reason, share]) => [reason, `${humanize(reason)} ${(share * 100).toFixed(0)}%`]),
      latency: fmt(device.last_latency_ms, 0, "ms"),
      seen: fmtAgo(nowS - device.last_seen_s),
    };
  }

  deviceRow(values) {
    const name = values.device;
    return el("tr", { "data-testid": "device-row", "data-device": name, class: "clickable",
      onclick: () => this.openFrame(name) },
      el("td", { class: "device-name" },
        el("span", { class: "swatch", style: `background:${colourOf(name)}` }), name,
        el("div", { class: "cell-note", text: values.note }),
        values.otherMap === null ? null
          : el("div", { class: "cell-note other-map", "data-field": "map", text: `in map ${values.otherMap}` })),
      el("td", { "data-field": "beacon" }, values.beacon,
        values.beaconSource ? el("div", { class: "cell-note", text: values.beaconSource }) : null),
      el("td", { class: "num", "data-field": "fix-rate" }, values.rate),
      el("td", { "data-field": "refused" }, values.refused.length
        ? values.refused.map(([reason, text]) => el("span", { class: "chip", "data-reason": reason, text }))
        : el("span", { class: "muted", text: "none" })),
      el("td", { class: "num", "data-field": "latency" }, values.latency),
      el("td", { class: "num", "data-field": "seen" }, values.seen),
    );
  }
}
