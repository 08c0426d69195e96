package io.lumipose.client.net;

import java.io.IOException;
import java.io.OutputStream;
import java.util.Arrays;
import java.util.Collections;
import java.util.LinkedHashMap;
import java.util.Map;

/**
 * One HTTP request as the transport sends it. The body is a slice of the caller's array, not a
 * copy (a frame is megabytes): the caller must not change it until the call returns.
 */
public final class HttpCall {
    public final String method;
    public final String url;
    public final Map<String, String> headers;
    private final byte[] body;
    private final int offset;
    private final int length;
    /** How long to wait for the answer, ms; 0: the transport's own read timeout. */
    public final int readTimeoutMs;

    public HttpCall(String method, String url, Map<String, String> headers, byte[] body) {
        this(method, url, headers, body, 0, body == null ? 0 : body.length);
    }

    /** A call whose body is {@code length} bytes of {@code body} from {@code offset}. */
    public HttpCall(String method, String url, Map<String, String> headers, byte[] body, int offset, int length) {
        this(method, url, headers, body, offset, length, 0);
    }

    private HttpCall(String method, String url, Map<String, String> headers, byte[] body, int offset, int length,
                     int readTimeoutMs) {
        if (body != null && (offset < 0 || length < 0 || offset + length > body.length)) {
            throw new IllegalArgumentException("body slice [" + offset + ", " + (offset + length) + ") outside "
                    + body.length + " bytes");
        }
        this.method = method;
        this.url = url;
        this.headers = Collections.unmodifiableMap(new LinkedHashMap<String, String>(headers));
        this.body = body;
        this.offset = offset;
        this.length = length;
        this.readTimeoutMs = readTimeoutMs;
    }

    /** The same call, its answer awaited up to {@code ms} instead of the transport's read timeout. */
    public HttpCall withReadTimeout(int ms) {
        if (ms <= 0) {
            throw new IllegalArgumentException("read timeout must be > 0 ms, got " + ms);
        }
        return new HttpCall(method, url, headers, body, offset, length, ms);
    }

    public boolean hasBody() {
        return body != null;
    }

    public int bodyLength() {
        return length;
    }

    /** Writes the body where the transport sends it. */
    public void writeBody(OutputStream out) throws IOException {
        if (body != null) {
            out.write(body, offset, length);
        }
    }

    /** A copy of the body (for tests and logs), null without one. */
    public byte[] body() {
        return body == null ? null : Arrays.copyOfRange(body, offset, offset + length);
    }
}
