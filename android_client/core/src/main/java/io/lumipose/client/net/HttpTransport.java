package io.lumipose.client.net;

import java.io.IOException;

/** Sends one request; an IOException means no HTTP answer came back (refused, reset, timed out). */
public interface HttpTransport {
    HttpReply send(HttpCall call) throws IOException;
}
