// Health view: version, uptime, active map and the routes' rates and latency quantiles (GET /v1/status).

import { getJson } from "./api.js";
import { byTestId, el, fmt, fmtDuration, humanize } from "./dom.js";

export class HealthView {
  constructor() {
    this.status = null;
    this.receivedMs = 0;
    // the uptime ticks between the status events (every 2 s)
    setInterval(() => this.renderUptime(), 1000);
  }

  update(status) {
    this.status = status;
    this.receivedMs = Date.now();
    byTestId("health-version").textContent = status.version;
    byTestId("health-map").textContent = status.active_map;
    byTestId("health-devices").textContent = status.devices;
    document.getElementById("health-fixes").textContent = status.fixes;
    document.getElementById("health-window").textContent =
      `rates and quantiles over the last ${fmt(status.window_s, 0, "s")}; requests and 5xx since start`;
    const refused = Object.entries(status.refused || {});
    document.getElementById("health-refused").textContent = refused.length
      ? refused.map(([reason, count]) => `${humanize(reason)}: ${count}`).join(" · ") : "None since start.";
    this.renderUptime();
    this.renderRoutes(status.routes || []);
  }

  /** The stored files' state from /healthz: a damaged map, profile or sample is named there. */
  async checkFiles() {
    const node = document.getElementById("health-files");
    try {
      const health = await getJson("/healthz");
      node.textContent = health.damaged.length
        ? `Degraded: damaged stored files ${health.damaged.join(", ")}` : "Stored maps, profiles and samples: ok";
      node.classList.toggle("bad", health.damaged.length > 0);
    } catch (error) {
      node.textContent = `Health check failed: ${error.message}`;
      node.classList.add("bad");
    }
  }

  renderUptime() {
    if (!this.status) return;
    const uptime = this.status.uptime_s + (Date.now() - this.receivedMs) / 1000;
    byTestId("health-uptime").textContent = fmtDuration(uptime);
  }

  renderRoutes(routes) {
    const tbody = byTestId("health-routes").querySelector("tbody");
    if (!routes.length) {
      tbody.replaceChildren(el("tr", {}, el("td", { colspan: 7, class: "muted", text: "No request yet." })));
      return;
    }
    tbody.replaceChildren(...routes.map((route) => el("tr", { "data-route": route.route },
      el("td", {}, el("code", { text: route.route })),
      el("td", { class: "num", text: route.requests }),
      el("td", { class: "num", text: fmt(route.rate_hz, 2, "/s") }),
      el("td", { class: "num", text: fmt(route.p50_ms, 1, "ms") }),
      el("td", { class: "num", text: fmt(route.p90_ms, 1, "ms") }),
      el("td", { class: "num", text: fmt(route.p99_ms, 1, "ms") }),
      el("td", { class: `num${route.errors ? " bad" : ""}`, text: route.errors }))));
  }
}
