// The service's HTTP API as the page uses it: JSON reads, keyed writes, ErrorBody on refusals.

const KEY_STORAGE = "lumipose.apiKey";

/** A refused request: the HTTP status and the service's ErrorBody {error, field, message}. */
export class ApiError extends Error {
  constructor(status, body) {
    super(body.message || `HTTP ${status}`);
    this.status = status;
    this.body = body;
  }
}

export const apiKey = {
  get: () => sessionStorage.getItem(KEY_STORAGE) || "",
  set: (key) => (key ? sessionStorage.setItem(KEY_STORAGE, key) : sessionStorage.removeItem(KEY_STORAGE)),
};

async function request(method, path, body) {
  const headers = { Accept: "application/json" };
  if (body !== undefined) headers["Content-Type"] = "application/json";
  if (method !== "GET" && apiKey.get()) headers["X-API-Key"] = apiKey.get();
  const response = await fetch(path, { method, headers, body: body === undefined ? undefined : body });
  const text = await response.text();
  const data = text ? parseJson(text) : null;
  if (!response.ok) {
    const errorBody = data && typeof data === "object" && data.error ? data : { error: "http", message: text };
    throw new ApiError(response.status, errorBody);
  }
  return data;
}

function parseJson(text) {
  try {
    return JSON.parse(text);
  } catch {
    return { error: "not_json", message: text.slice(0, 200) };
  }
}

export const getJson = (path) => request("GET", path);

/** A keyed write; `rawBody` is sent as it is (a map file's text), so the service judges it, not the page. */
export const putJson = (path, rawBody) => request("PUT", path, rawBody);
