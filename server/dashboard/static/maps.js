// Maps view: the stored maps, a drawing of the selected one, upload (errors shown at the field they name), activate.

import { ApiError, apiKey, getJson, putJson } from "./api.js";
import { byTestId, el } from "./dom.js";
import { drawRoom } from "./roommap.js";

const mapPath = (name) => `/v1/maps/${encodeURIComponent(name)}`;
const NAME_PATTERN = /^[A-Za-z0-9][A-Za-z0-9_.-]{0,63}$/; // the service's (shared_schemas/api.py NAME_PATTERN)

/** Why the service would refuse `name` as a map's name, or "" when it would take it. */
export function nameProblem(name) {
  if (!name) return "Name the map first (the file's “name” by default).";
  if (NAME_PATTERN.test(name)) return "";
  return "Use 1-64 letters, digits, '_', '.' or '-', starting with a letter or digit.";
}

/** Pretty JSON as lines, each with the dotted path of the value it holds ("beacons.1.side_m"; "" the whole). */
export function jsonLines(value, path = "", key = null, depth = 0, comma = "") {
  const pad = "  ".repeat(depth);
  const label = key === null ? "" : `${JSON.stringify(key)}: `;
  const isObject = value !== null && typeof value === "object";
  const entries = isObject ? (Array.isArray(value) ? value.map((v, i) => [i, v]) : Object.entries(value)) : [];
  if (!isObject || entries.length === 0) {
    const text = isObject ? (Array.isArray(value) ? "[]" : "{}") : JSON.stringify(value);
    return [{ path, text: `${pad}${label}${text}${comma}` }];
  }
  const [open, close] = Array.isArray(value) ? ["[", "]"] : ["{", "}"];
  const lines = [{ path, text: `${pad}${label}${open}` }];
  entries.forEach(([childKey, child], index) => {
    const childPath = path === "" ? String(childKey) : `${path}.${childKey}`;
    const childLabel = Array.isArray(value) ? null : childKey;
    lines.push(...jsonLines(child, childPath, childLabel, depth + 1, index < entries.length - 1 ? "," : ""));
  });
  lines.push({ path: null, text: `${pad}${close}${comma}` });
  return lines;
}

/** The line an error's field names: the deepest path of the upload that starts its field ("body": the whole). */
export function lineForField(lines, field) {
  const wanted = (field || "").replace(/^body\.?/, "");
  let best = lines[0];
  for (const line of lines) {
    if (line.path === null || line.path === "") continue;
    const covers = wanted === line.path || wanted.startsWith(`${line.path}.`);
    if (covers && line.path.length > (best.path || "").length) best = line;
  }
  return best;
}

/** An ErrorBody in one line, naming the field once. */
function describe(body) {
  const field = body.field && !body.message.includes(body.field) ? ` at ${body.field}` : "";
  return `${body.error}${field}: ${body.message}`;
}

function keyMessage() {
  return apiKey.get()
    ? "The API key was refused: writing needs the API key the server was started with."
    : "Writing needs the API key: enter it in the API key field at the top.";
}

export class MapsView {
  constructor({ onActivated }) {
    this.tbody = byTestId("maps-list").querySelector("tbody");
    this.fileInput = byTestId("map-upload");
    this.nameInput = byTestId("map-name");
    this.errors = byTestId("map-errors");
    this.onActivated = onActivated;
    this.maps = [];
    this.selected = null;
    this.uploadText = null;
    this.nameError = el("span", { class: "field-error", "data-testid": "map-name-error", role: "alert" });
    this.nameInput.after(this.nameError);
    this.nameInput.addEventListener("input", () => this.checkName());
    // an upload waits for the file being read: clicked at once, it would send the previous file's text
    this.fileInput.addEventListener("change", () => (this.reading = this.readFile()));
    document.getElementById("map-form").addEventListener("submit", (event) => {
      event.preventDefault();
      this.upload();
    });
    byTestId("map-activate").addEventListener("click", () => this.activate());
  }

  async load() {
    try {
      this.maps = await getJson("/v1/maps");
    } catch (error) {
      return this.say(`Could not list the maps: ${error.message}`, "bad");
    }
    if (!this.maps.some((m) => m.name === this.selected)) this.selected = this.maps.find((m) => m.active)?.name;
    this.renderList();
    if (this.selected) this.view(this.selected);
  }

  renderList() {
    this.tbody.replaceChildren(...this.maps.map((summary) => el("tr", {
      "data-testid": "map-row", "data-map": summary.name, "data-active": summary.active ? "true" : "false",
      class: `clickable${summary.name === this.selected ? " selected" : ""}`,
      onclick: () => this.select(summary.name) },
    el("td", {}, summary.name, summary.active ? el("span", { class: "badge", text: "active" }) : null),
    el("td", { class: "num", text: summary.beacons }),
    el("td", { text: summary.source }),
    el("td", { class: "muted", text: summary.name === this.selected ? "shown" : "" }))));
    byTestId("map-activate").disabled = !this.selected;
  }

  select(name) {
    this.selected = name;
    this.renderList();
    this.view(name);
  }

  async view(name) {
    try {
      this.draw(await getJson(mapPath(name)), "");
    } catch (error) {
      this.say(`Could not read map ${name}: ${error.message}`, "bad");
    }
  }

  draw(beaconMap, note) {
    document.getElementById("map-title").textContent =
      `${beaconMap.name}: ${beaconMap.beacons.length} panel${beaconMap.beacons.length === 1 ? "" : "s"}${note}`;
    drawRoom(byTestId("map-view"), beaconMap, [], "map-panel");
  }

  async activate() {
    if (!this.selected) return;
    try {
      await putJson("/v1/maps/active", JSON.stringify({ name: this.selected }));
      this.say(`Map “${this.selected}” is now active: locate uses it by default.`, "good");
      await this.load();
      this.onActivated();
    } catch (error) {
      this.sayError(error);
    }
  }

  async readFile() {
    const file = this.fileInput.files[0];
    this.errors.hidden = true;
    if (!file) return;
    this.uploadText = await file.text();
    try {
      const parsed = JSON.parse(this.uploadText);
      if (typeof parsed?.name === "string") this.nameInput.value = parsed.name;
      this.checkName();
      if (Array.isArray(parsed?.beacons) && parsed.beacons.length) this.draw(parsed, " (file, not stored yet)");
    } catch {
      // the service names what is wrong with the file when it is sent
    }
    this.say(`Read ${file.name} (${file.size} bytes): upload to store it.`, "");
  }

  async upload() {
    await this.reading;
    const name = this.nameInput.value.trim();
    if (this.uploadText === null) return this.say("Choose a map file first.", "bad");
    const problem = this.checkName();
    if (problem) return this.say("Not sent: the map's name needs fixing (see next to the field).", "bad");
    this.errors.hidden = true;
    try {
      const stored = await putJson(mapPath(name), this.uploadText);
      this.say(`Stored map “${stored.name}” (${stored.beacons.length} panels).`, "good");
      this.selected = stored.name;
      await this.load();
    } catch (error) {
      this.sayError(error);
      if (error instanceof ApiError && error.status !== 401) this.showUploadError(error.body);
    }
  }

  /** Shows next to the name field why the service would refuse it, and returns it ("" when it is fine). */
  checkName() {
    const problem = nameProblem(this.nameInput.value.trim());
    this.nameError.textContent = problem;
    this.nameInput.toggleAttribute("aria-invalid", Boolean(problem));
    return problem;
  }

  /** The uploaded file with the error's message next to the line of the field it names. */
  showUploadError(body) {
    let parsed;
    try {
      parsed = JSON.parse(this.uploadText);
    } catch (parseError) {
      parsed = undefined;
      body = { ...body, message: `${body.message} (${parseError.message})` };
    }
    const lines = parsed === undefined ? this.uploadText.split("\n").map((text) => ({ path: null, text }))
      : jsonLines(parsed);
    const marked = parsed === undefined ? lines[0] : lineForField(lines, body.field);
    const field = body.field || "body";
    this.errors.replaceChildren(
      el("p", { class: "error-text", text: describe(body) }),
      el("pre", { class: "json" }, lines.map((line) => line === marked
        ? el("div", { class: "line error", "data-testid": "map-error-field", "data-field": field },
          el("code", { text: line.text }), el("span", { class: "error-note", text: `← ${body.message}` }))
        : el("div", { class: "line" }, el("code", { text: line.text })))),
    );
    this.errors.hidden = false;
    // bring the marked line to the middle of the listing (not the page: it stays where the user is)
    const pre = this.errors.querySelector("pre");
    const line = pre.querySelector(".error");
    pre.scrollTop = line.offsetTop - pre.clientHeight / 2;
  }

  sayError(error) {
    if (error instanceof ApiError && error.status === 401) return this.say(keyMessage(), "bad");
    const body = error instanceof ApiError ? error.body : { error: "network", message: error.message };
    this.say(`Refused: ${describe(body)}`, "bad");
  }

  say(text, tone) {
    const node = byTestId("map-message");
    node.textContent = text;
    node.className = `message ${tone}`;
  }
}
