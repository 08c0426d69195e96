package io.lumipose.client.net;

import org.json.JSONObject;

import io.lumipose.client.json.ContractException;
import io.lumipose.client.json.Json;

/**
 * The server refused the request (HTTP 4xx/5xx) with the contract's ErrorBody
 * {"error": code, "field": field or null, "message": sentence}.
 */
public final class ServerRejectedException extends Exception {
    private static final long serialVersionUID = 1L;
    public final int status;
    public final String code;
    public final String field;

    public ServerRejectedException(int status, String code, String field, String message) {
        super("HTTP " + status + " " + code + (field == null ? "" : " (" + field + ")") + ": " + message);
        this.status = status;
        this.code = code;
        this.field = field;
    }

    /** Reads an ErrorBody; a body that is not one still gives a readable exception. */
    public static ServerRejectedException fromBody(int status, String body) {
        try {
            JSONObject o = Json.parseObject(body, "error body");
            String code = Json.optString(o, "error", "error");
            String message = Json.optString(o, "message", "message");
            if (code != null && message != null) {
                return new ServerRejectedException(status, code, Json.optString(o, "field", "field"), message);
            }
        } catch (ContractException ignored) {
            // Not the contract's error body (a proxy page, say): fall through and show its start.
        }
        if (status == 401 && body.isEmpty()) {
            // The JDK drops a 401's body after a streamed upload (UrlConnectionTransport); the status says it all.
            return new ServerRejectedException(status, "unauthorized", "X-API-Key", "missing or wrong API key");
        }
        String start = body.length() > 200 ? body.substring(0, 200) + "..." : body;
        return new ServerRejectedException(status, "http_" + status, null, start.isEmpty() ? "(empty body)" : start);
    }
}
