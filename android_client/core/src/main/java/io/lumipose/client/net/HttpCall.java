package io.lumipose.client.net;

import java.util.Collections;
import java.util.LinkedHashMap;
import java.util.Map;

/** One HTTP request as the transport sends it. */
public final class HttpCall {
    public final String method;
    public final String url;
    public final Map<String, String> headers;
    private final byte[] body;

    public HttpCall(String method, String url, Map<String, String> headers, byte[] body) {
        this.method = method;
        this.url = url;
        this.headers = Collections.unmodifiableMap(new LinkedHashMap<String, String>(headers));
        this.body = body == null ? null : body.clone();
    }

    public byte[] body() {
        return body == null ? null : body.clone();
    }
}
