package io.lumipose.client.net;

import java.io.ByteArrayOutputStream;
import java.io.IOException;
import java.io.InputStream;
import java.io.OutputStream;
import java.net.HttpURLConnection;
import java.net.URL;
import java.util.Map;

/** {@link HttpTransport} over the platform's HttpURLConnection (JDK and Android alike: no extra library). */
public final class UrlConnectionTransport implements HttpTransport {
    private final int connectTimeoutMs;
    private final int readTimeoutMs;

    public UrlConnectionTransport(int connectTimeoutMs, int readTimeoutMs) {
        this.connectTimeoutMs = connectTimeoutMs;
        this.readTimeoutMs = readTimeoutMs;
    }

    @Override
    public HttpReply send(HttpCall call) throws IOException {
        HttpURLConnection c = (HttpURLConnection) new URL(call.url).openConnection();
        try {
            c.setConnectTimeout(connectTimeoutMs);
            c.setReadTimeout(readTimeoutMs);
            c.setRequestMethod(call.method);
            c.setUseCaches(false);
            for (Map.Entry<String, String> h : call.headers.entrySet()) {
                c.setRequestProperty(h.getKey(), h.getValue());
            }
            byte[] body = call.body();
            if (body != null) {
                c.setDoOutput(true);
                // No fixed-length streaming: the JDK then cannot read the body of a 401 (HttpRetryException).
                OutputStream out = c.getOutputStream();
                try {
                    out.write(body);
                } finally {
                    out.close();
                }
            }
            int status = c.getResponseCode();
            InputStream in = status >= 400 ? c.getErrorStream() : c.getInputStream();
            return new HttpReply(status, in == null ? new byte[0] : readAll(in));
        } finally {
            c.disconnect();
        }
    }

    private static byte[] readAll(InputStream in) throws IOException {
        try {
            ByteArrayOutputStream out = new ByteArrayOutputStream();
            byte[] buf = new byte[16384];
            int n;
            while ((n = in.read(buf)) > 0) {
                out.write(buf, 0, n);
            }
            return out.toByteArray();
        } finally {
            in.close();
        }
    }
}
