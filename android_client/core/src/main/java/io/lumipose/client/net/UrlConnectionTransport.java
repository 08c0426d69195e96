package io.lumipose.client.net;

import java.io.ByteArrayOutputStream;
import java.io.IOException;
import java.io.InputStream;
import java.io.OutputStream;
import java.net.HttpRetryException;
import java.net.HttpURLConnection;
import java.net.URL;
import java.util.Map;

/**
 * {@link HttpTransport} over the platform's HttpURLConnection (JDK and Android alike: no extra
 * library). The body is streamed with its fixed length (not buffered again), and every answer is
 * read to its end and its stream closed without {@code disconnect()}, so the next call to the same
 * server reuses the kept-alive connection.
 */
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
            c.setReadTimeout(call.readTimeoutMs > 0 ? call.readTimeoutMs : readTimeoutMs);
            c.setRequestMethod(call.method);
            c.setUseCaches(false);
            for (Map.Entry<String, String> h : call.headers.entrySet()) {
                c.setRequestProperty(h.getKey(), h.getValue());
            }
            if (call.hasBody()) {
                c.setDoOutput(true);
                c.setFixedLengthStreamingMode(call.bodyLength());
                OutputStream out = c.getOutputStream();
                try {
                    call.writeBody(out);
                } finally {
                    out.close();
                }
            }
            int status;
            try {
                status = c.getResponseCode();
            } catch (HttpRetryException e) {
                // The JDK (not Android) will not read a 401's body after a streamed request body: it
                // throws this instead, and has closed the connection. The status is what matters.
                return new HttpReply(e.responseCode(), new byte[0]);
            }
            InputStream in = status >= 400 ? c.getErrorStream() : c.getInputStream();
            return new HttpReply(status, in == null ? new byte[0] : readAll(in));
        } catch (IOException e) {
            c.disconnect(); // a broken connection is not worth keeping
            throw e;
        }
    }

    /** Reads to the end and closes: only then may the connection serve the next call. */
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
