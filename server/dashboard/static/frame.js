// Frame view: the newest annotated window a device's frame left (the paper's Fig. 8) and what it gave.

import { ApiError, getJson } from "./api.js";
import { byTestId, el, fmt, humanize } from "./dom.js";

// each new picture is drawn by the service on request, in turn with the frames it locates: ask at most this often
const MIN_REFRESH_MS = 2000;

const framesPath = (device) => `/v1/live/devices/${encodeURIComponent(device)}/frames`;
const pngPath = (device, seq) => `${framesPath(device)}/${seq}.png`;

export class FrameView {
  constructor({ onChooseDevice }) {
    this.select = byTestId("frame-device");
    this.image = byTestId("frame-image");
    this.thumbs = document.getElementById("frame-thumbs");
    this.device = null;
    this.kept = [];
    this.shownSeq = null;
    this.following = true; // show each new frame as it comes, until a thumbnail of an older one is chosen
    this.loading = null;
    this.refreshTimer = null;
    this.select.addEventListener("change", () => onChooseDevice(this.select.value));
  }

  /** Fills the device choice; keeps the chosen one listed even before it is seen. */
  setDevices(names) {
    const all = this.device && !names.includes(this.device) ? [this.device, ...names] : names;
    const current = [...this.select.options].map((o) => o.value);
    if (current.join("\n") !== all.join("\n")) {
      this.select.replaceChildren(...all.map((name) => el("option", { value: name, text: name })));
    }
    if (this.device) this.select.value = this.device;
    this.select.disabled = all.length === 0;
    document.getElementById("frame-empty").hidden = all.length > 0;
  }

  /** Shows `device` (from the route `#frame/<device>`), or the most recent one when none is named. */
  show(device, names) {
    const chosen = device || this.device || names[0] || null;
    if (chosen !== this.device) {
      this.device = chosen;
      this.kept = [];
      this.shownSeq = null;
      this.following = true;
    }
    this.setDevices(names);
    if (this.device) this.load();
  }

  /** A live update of the chosen device: fetch its frames again when a newer one was kept (not more than
   * once every 2 s, and not while the view or the page is hidden). */
  onDevice(device, visible) {
    if (!visible || document.hidden || device.device !== this.device || !this.following) return;
    const newest = device.frames_kept?.at(-1);
    if (newest === undefined || newest === this.kept[0]?.seq) return;
    this.refreshSoon();
  }

  /** Fetch the frames again, at most once every MIN_REFRESH_MS (the server draws each picture asked for). */
  refreshSoon() {
    if (this.refreshTimer) return;
    const wait = Math.max(0, MIN_REFRESH_MS - (Date.now() - (this.loadedAt || 0)));
    this.refreshTimer = setTimeout(() => {
      this.refreshTimer = null;
      this.load();
    }, wait);
  }

  /** Fetches the chosen device's kept frames; one request at a time per device (another device's does not
   * hold back the newly chosen one's). */
  async load() {
    const device = this.device;
    if (this.loading?.device === device) return this.loading.done;
    const done = getJson(framesPath(device))
      .then((kept) => device === this.device && this.showKept(kept))
      .catch((error) => device === this.device && this.showError(error))
      .finally(() => this.loading?.done === done && (this.loading = null));
    this.loading = { device, done };
    return done;
  }

  showKept(kept) {
    this.kept = kept;
    this.loadedAt = Date.now();
    document.getElementById("frame-body").hidden = false;
    const stillKept = kept.some((frame) => frame.seq === this.shownSeq);
    const frame = this.following || !stillKept ? kept[0] : kept.find((f) => f.seq === this.shownSeq);
    if (!frame) return this.showError(new ApiError(404, { message: "This device has no kept frame yet." }));
    this.showFrame(frame);
    this.thumbs.replaceChildren(...kept.map((f, index) => this.thumb(f, index === 0)));
  }

  thumb(frame, newest) {
    return el("button", { type: "button", "data-testid": "frame-thumb", "data-seq": frame.seq,
      class: `thumb${frame.seq === this.shownSeq ? " current" : ""}${frame.result.ok ? "" : " refused"}`,
      title: `frame ${frame.seq}${newest ? " (newest)" : ""}`,
      onclick: () => {
        this.following = newest;
        this.showFrame(frame);
        this.showKept(this.kept);
      } },
    el("img", { src: pngPath(this.device, frame.seq), alt: `frame ${frame.seq}`, loading: "lazy" }),
    el("span", { text: `#${frame.seq} ${frame.result.ok ? "fix" : humanize(frame.result.reason || "refused")}` }));
  }

  showFrame(frame) {
    this.shownSeq = frame.seq;
    const src = pngPath(this.device, frame.seq);
    if (this.image.getAttribute("src") !== src) {
      // dropped meanwhile (a fast device keeps each frame a fraction of a second): ask for what is kept now
      this.image.onerror = () => this.following && this.refreshSoon();
      this.image.src = src;
    }
    this.image.dataset.seq = frame.seq;
    this.showResult(frame);
  }

  showResult(frame) {
    const result = frame.result;
    const set = (id, content, muted = false) => {
      const node = byTestId(id);
      node.replaceChildren(content);
      node.classList.toggle("muted", muted);
    };
    const pos = result.position_m;
    const ypr = result.yaw_pitch_roll_deg;
    const sigma = result.position_sigma_m;
    set("frame-beacon", result.beacon_id ?? "—", result.beacon_id == null);
    set("frame-pose", pos ? poseText(pos, ypr, sigma) : "—", !pos);
    set("frame-reprojection", fmt(result.reprojection_error_px, 3, "px"), result.reprojection_error_px == null);
    set("frame-ambiguity", fmt(result.ambiguity_ratio, 3), result.ambiguity_ratio == null);
    const warnings = result.warnings || [];
    set("frame-warnings", warnings.length ? el("ul", {}, warnings.map((w) => el("li", { text: w }))) : "none",
      !warnings.length);
    const refusal = result.ok ? "—" : el("span", {}, el("b", { text: result.reason || "refused" }),
      result.message ? ` ${result.message}` : "");
    set("frame-reason", refusal, result.ok);
    byTestId("frame-reason").classList.toggle("bad", !result.ok);
    const when = new Date(frame.time_s * 1000).toLocaleTimeString();
    document.getElementById("frame-meta").textContent =
      `Frame #${frame.seq} at ${when} on map “${frame.map}”; window ${frame.window_px.join(", ")} (frame pixels).`;
  }

  showError(error) {
    document.getElementById("frame-body").hidden = true;
    const empty = document.getElementById("frame-empty");
    empty.hidden = false;
    empty.textContent = error instanceof ApiError && error.status === 404
      ? `${this.device} has no kept frame (yet): ${error.body.message}`
      : `Could not load the frames of ${this.device}: ${error.message}`;
  }
}

function poseText(pos, ypr, sigma) {
  const xyz = pos.map((v) => v.toFixed(4)).join(", ");
  const lines = [el("div", { text: `(${xyz}) m` })];
  if (sigma) {
    const mm = sigma.map((v) => (v * 1000).toFixed(1)).join(" / ");
    lines.push(el("div", { class: "cell-note", text: `σ ${mm} mm (x / y / z)` }));
  }
  if (ypr) {
    const [yaw, pitch, roll] = ypr.map((v) => v.toFixed(2));
    lines.push(el("div", { text: `yaw ${yaw}°, pitch ${pitch}°, roll ${roll}°` }));
  }
  return el("div", {}, lines);
}
