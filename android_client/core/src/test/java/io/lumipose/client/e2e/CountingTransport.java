package io.lumipose.client.e2e;

import java.io.IOException;
import java.util.ArrayList;
import java.util.List;
import java.util.Map;

import org.json.JSONObject;

import io.lumipose.client.net.HttpCall;
import io.lumipose.client.net.HttpReply;
import io.lumipose.client.net.HttpTransport;
import io.lumipose.client.net.UrlConnectionTransport;

/** The real transport, recording what each frame upload cost: bytes sent, time to the answer, the answer. */
final class CountingTransport implements HttpTransport {
    /** One request and its answer. */
    static final class Exchange {
        /** The frame JSON sent with it (X-Lumipose-Frame), null for other requests. */
        final JSONObject frame;
        final int bodyBytes;
        /** Request line and headers, as sent (approximately: the HTTP client adds a few of its own). */
        final int headerBytes;
        /** From the request's start to the whole answer, ms (on 127.0.0.1: the server's time per request). */
        final double ms;
        final int status;
        final JSONObject reply;
        /** The body went gzip-compressed (Content-Encoding). */
        final boolean gzipped;

        Exchange(JSONObject frame, int bodyBytes, int headerBytes, double ms, int status, JSONObject reply,
                 boolean gzipped) {
            this.gzipped = gzipped;
            this.frame = frame;
            this.bodyBytes = bodyBytes;
            this.headerBytes = headerBytes;
            this.ms = ms;
            this.status = status;
            this.reply = reply;
        }

        long timestampNs() {
            return frame.getLong("timestamp_ns");
        }

        boolean isId() {
            return "id".equals(frame.optString("frame_kind", "pose"));
        }
    }

    private final HttpTransport transport = new UrlConnectionTransport(3000, 60000);
    private final List<Exchange> exchanges = new ArrayList<Exchange>();

    @Override
    public HttpReply send(HttpCall call) throws IOException {
        byte[] body = call.body();
        int headerBytes = call.method.length() + call.url.length() + 12;
        for (Map.Entry<String, String> h : call.headers.entrySet()) {
            headerBytes += h.getKey().length() + h.getValue().length() + 4;
        }
        long start = System.nanoTime();
        HttpReply reply = transport.send(call);
        double ms = (System.nanoTime() - start) / 1e6;
        String frame = call.headers.get("X-Lumipose-Frame");
        if (frame != null) {
            String text = reply.text();
            synchronized (exchanges) {
                exchanges.add(new Exchange(new JSONObject(frame), body == null ? 0 : body.length, headerBytes, ms,
                        reply.status, text.startsWith("{") ? new JSONObject(text) : new JSONObject(),
                        "gzip".equals(call.headers.get("Content-Encoding"))));
            }
        }
        return reply;
    }

    List<Exchange> exchanges() {
        synchronized (exchanges) {
            return new ArrayList<Exchange>(exchanges);
        }
    }
}
