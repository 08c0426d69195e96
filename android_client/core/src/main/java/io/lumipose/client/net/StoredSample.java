package io.lumipose.client.net;

import org.json.JSONObject;

import io.lumipose.client.json.ContractException;
import io.lumipose.client.json.Json;

/** The server's answer to POST /v1/samples: the stored sample's id and label, and its locate result. */
public final class StoredSample {
    public final String id;
    public final String label;
    public final LocateResult result;

    public StoredSample(String id, String label, LocateResult result) {
        this.id = id;
        this.label = label;
        this.result = result;
    }

    public static StoredSample fromJson(String text) {
        JSONObject o = Json.parseObject(text, "sample");
        String id = Json.optString(o, "id", "id");
        if (id == null) {
            throw new ContractException("id", "missing");
        }
        return new StoredSample(id, Json.optString(o, "label", "label"),
                LocateResult.fromJson(Json.requireObject(o, "result", "result")));
    }
}
