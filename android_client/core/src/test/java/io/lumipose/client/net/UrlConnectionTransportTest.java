package io.lumipose.client.net;

import static org.junit.jupiter.api.Assertions.assertArrayEquals;
import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertThrows;
import static org.junit.jupiter.api.Assertions.assertTrue;

import java.io.IOException;
import java.io.OutputStream;
import java.net.InetSocketAddress;
import java.nio.charset.StandardCharsets;
import java.util.concurrent.atomic.AtomicReference;

import org.junit.jupiter.api.AfterEach;
import org.junit.jupiter.api.BeforeEach;
import org.junit.jupiter.api.Test;

import com.sun.net.httpserver.HttpServer;

import io.lumipose.client.camera.Intrinsics;
import io.lumipose.client.frame.FrameMeta;

/** The real HttpURLConnection path against a loopback server: gzip body, headers, error bodies. */
class UrlConnectionTransportTest {
    private HttpServer server;
    private final AtomicReference<byte[]> received = new AtomicReference<>();
    private final AtomicReference<String> frameHeader = new AtomicReference<>();
    private final AtomicReference<String> encoding = new AtomicReference<>();

    @BeforeEach
    void start() throws IOException {
        server = HttpServer.create(new InetSocketAddress("127.0.0.1", 0), 0);
        server.createContext("/v1/locate", exchange -> {
            received.set(exchange.getRequestBody().readAllBytes());
            frameHeader.set(exchange.getRequestHeaders().getFirst("X-Lumipose-Frame"));
            encoding.set(exchange.getRequestHeaders().getFirst("Content-Encoding"));
            boolean keyOk = "k".equals(exchange.getRequestHeaders().getFirst("X-API-Key"));
            byte[] body = (keyOk ? LumiposeClientTest.OK
                    : "{\"error\": \"unauthorized\", \"field\": null, \"message\": \"wrong API key\"}")
                    .getBytes(StandardCharsets.UTF_8);
            exchange.sendResponseHeaders(keyOk ? 200 : 401, body.length);
            try (OutputStream out = exchange.getResponseBody()) {
                out.write(body);
            }
        });
        server.start();
    }

    @AfterEach
    void stop() {
        server.stop(0);
    }

    private LumiposeClient client(String key) {
        return new LumiposeClient(new ClientConfig("http://127.0.0.1:" + server.getAddress().getPort(), key, null,
                true, new RetryPolicy(2, 1, 1, 1)), new UrlConnectionTransport(2000, 5000), Sleeper.REAL);
    }

    @Test
    void frameTravelsGzippedWithItsJsonHeader() throws Exception {
        byte[] luma = new byte[64 * 48];
        for (int i = 0; i < luma.length; i++) {
            luma[i] = (byte) (i % 251);
        }
        FrameMeta meta = FrameMeta.builder(64, 48).camera(new Intrinsics(50, 50, 31.5, 23.5, null, null, null, null))
                .build();
        assertTrue(client("k").locate(luma, meta).ok);
        assertEquals("gzip", encoding.get());
        assertArrayEquals(luma, LumiposeClientTest.gunzip(received.get()));
        assertEquals(64, FrameMeta.fromJson(frameHeader.get()).width);
    }

    @Test
    void errorBodyOfA401IsRead() {
        FrameMeta meta = FrameMeta.builder(2, 2).camera(new Intrinsics(5, 5, 0.5, 0.5, null, null, null, null)).build();
        ServerRejectedException e = assertThrows(ServerRejectedException.class,
                () -> client("wrong").locate(new byte[4], meta));
        assertEquals(401, e.status);
        assertEquals("unauthorized", e.code);
    }
}
