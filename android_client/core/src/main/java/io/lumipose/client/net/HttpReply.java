package io.lumipose.client.net;

import java.nio.charset.Charset;

/** Status and body of one HTTP response. */
public final class HttpReply {
    private static final Charset UTF8 = Charset.forName("UTF-8");
    public final int status;
    private final byte[] body;

    public HttpReply(int status, byte[] body) {
        this.status = status;
        this.body = body == null ? new byte[0] : body.clone();
    }

    public String text() {
        return new String(body, UTF8);
    }
}
