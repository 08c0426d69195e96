package io.lumipose.client.net;

import java.io.IOException;
import java.util.ArrayDeque;
import java.util.ArrayList;
import java.util.Deque;
import java.util.List;

/** Replays scripted replies (or IOExceptions) and records every call (public: the sessions' tests use it too). */
public final class FakeTransport implements HttpTransport {
    public final List<HttpCall> calls = new ArrayList<>();
    private final Deque<Object> script = new ArrayDeque<>();

    public FakeTransport reply(int status, String body) {
        script.add(new HttpReply(status, body.getBytes(java.nio.charset.StandardCharsets.UTF_8)));
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
        return (HttpReply) next;
    }
}
