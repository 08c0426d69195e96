// The page: tabs by hash route (#live, #frame/<device>, #bench, #maps, #health), the live event stream,
// the API key field. Each view lives in its own module.

import { apiKey, getJson } from "./api.js";
import { BenchView } from "./bench.js";
import { byTestId } from "./dom.js";
import { FrameView } from "./frame.js";
import { HealthView } from "./health.js";
import { LiveView } from "./live.js";
import { MapsView } from "./maps.js";

const VIEWS = ["live", "frame", "bench", "maps", "health"];

const openFrame = (device) => (location.hash = `#frame/${encodeURIComponent(device)}`);
const live = new LiveView({ openFrame });
const frame = new FrameView({ onChooseDevice: openFrame });
const bench = new BenchView();
const maps = new MapsView({ onActivated: () => loadActiveMap() });
const health = new HealthView();
const loaded = new Set();
let currentView = null;

function route() {
  const [name, ...rest] = location.hash.replace(/^#/, "").split("/");
  const view = VIEWS.includes(name) ? name : "live";
  if (view !== currentView) window.scrollTo(0, 0);
  currentView = view;
  for (const other of VIEWS) {
    byTestId(`view-${other}`).hidden = other !== view;
    byTestId(`tab-${other}`).classList.toggle("active", other === view);
    byTestId(`tab-${other}`).toggleAttribute("aria-current", other === view);
  }
  if (view === "frame") frame.show(rest.length ? decodeURIComponent(rest.join("/")) : null, live.deviceNames());
  if (view === "bench" && !loaded.has("bench")) bench.load();
  if (view === "maps") maps.load();
  if (view === "health") health.checkFiles();
  loaded.add(view);
}

async function loadActiveMap() {
  try {
    const { name } = await getJson("/v1/maps/active");
    live.setMap(await getJson(`/v1/maps/${encodeURIComponent(name)}`));
  } catch (error) {
    document.getElementById("live-summary").textContent = `Could not read the active map: ${error.message}`;
  }
}

function setConnection(state) {
  const node = byTestId("live-connection");
  node.textContent = state;
  node.dataset.state = state;
}

function onDevices(liveDevices, replace) {
  live.update(liveDevices, replace);
  frame.setDevices(live.deviceNames());
  if (currentView === "frame" && !frame.device) frame.show(null, live.deviceNames());
  for (const device of liveDevices.devices) frame.onDevice(device, currentView === "frame");
}

/** The live stream; EventSource reconnects by itself (the server's `retry: 1000`), resyncing on each open. */
function connect() {
  const events = new EventSource("/v1/live/events");
  events.addEventListener("open", () => {
    setConnection("live");
    getJson("/v1/live/devices").then((all) => onDevices(all, true)).catch(() => {});
  });
  events.addEventListener("error", () => {
    setConnection("reconnecting");
    // a refused stream (not a dropped one) is not retried by the browser: retry it here
    if (events.readyState === EventSource.CLOSED) setTimeout(connect, 3000);
  });
  events.addEventListener("bye", () => setConnection("reconnecting"));
  events.addEventListener("devices", (event) => onDevices(JSON.parse(event.data), false));
  events.addEventListener("status", (event) => {
    const status = JSON.parse(event.data);
    health.update(status);
    live.onStatus(status);
    if (live.map && status.active_map !== live.map.name) loadActiveMap();
  });
}

function setUpKeyField() {
  const input = document.getElementById("api-key");
  input.value = apiKey.get();
  input.addEventListener("input", () => apiKey.set(input.value.trim()));
}

setUpKeyField();
window.addEventListener("hashchange", route);
route();
loadActiveMap();
getJson("/v1/status").then((status) => health.update(status)).catch(() => {});
connect();
// "seen ... ago" moves on between events
setInterval(() => live.renderTable(), 5000);
