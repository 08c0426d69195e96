package io.lumipose.client.net;

import java.io.IOException;
import java.net.SocketTimeoutException;
import java.util.ArrayDeque;
import java.util.ArrayList;
import java.util.Deque;
import java.util.List;

/** Replays scripted replies (or IOExceptions) and records every call (public: the sessions' tests use it too). */
public final class FakeTransport implements HttpTransport {
    public final List<HttpCall> calls = new ArrayList<>();
    private final Deque<Object> script = new ArrayDeque<>();
    private final int readTimeoutMs;

    /** A transport whose own read timeout is the client's default ({@link ClientConfig#PATIENT_READ_TIMEOUT_MS}). */
    public FakeTransport() {
        this(ClientConfig.PATIENT_READ_TIMEOUT_MS);
    }

    /** A transport that waits {@code readTimeoutMs} for an answer unless the call asks for its own wait. */
    public FakeTransport(int readTimeoutMs) {
        this.readTimeoutMs = readTimeoutMs;
    }

    public FakeTransport reply(int status, String body) {
        return replyAfter(0, status, body);
    }

    /**
     * An answer that comes {@code ms} after the request: a read timeout (as HttpURLConnection throws
     * it) when the call's wait, or else the transport's, is shorter.
     */
    public FakeTransport replyAfter(long ms, int status, String body) {
        script.add(new Slow(ms, new HttpReply(status, body.getBytes(java.nio.charset.StandardCharsets.UTF_8))));
        return this;
    }

    public FakeTransport fail(String message) {
        script.add(new IOException(message));
        return this;
    }

    @Override
    public HttpReply send(HttpCall call) throws IOException {
        calls.add(call);
        Object next = script.poll();
        if (next == null) {
            throw new AssertionError("unexpected call to " + call.url);
        }
        if (next instanceof IOException) {
            throw (IOException) next;
        }
        Slow answer = (Slow) next;
        int wait = call.readTimeoutMs > 0 ? call.readTimeoutMs : readTimeoutMs;
        if (answer.ms > wait) {
            throw new SocketTimeoutException("Read timed out (answer after " + answer.ms + " ms, waited " + wait
                    + " ms)");
        }
        return answer.reply;
    }

    private static final class Slow {
        final long ms;
        final HttpReply reply;

        Slow(long ms, HttpReply reply) {
            this.ms = ms;
            this.reply = reply;
        }
    }
}
