package io.lumipose.client.net;

import static org.junit.jupiter.api.Assertions.assertArrayEquals;
import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertFalse;
import static org.junit.jupiter.api.Assertions.assertThrows;
import static org.junit.jupiter.api.Assertions.assertTrue;

import java.io.IOException;
import java.io.OutputStream;
import java.net.InetSocketAddress;
import java.nio.charset.StandardCharsets;
import java.util.Set;
import java.util.concurrent.ConcurrentHashMap;
import java.util.concurrent.Executors;
import java.util.concurrent.atomic.AtomicInteger;
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
    private final AtomicReference<String> query = new AtomicReference<>();
    private final AtomicReference<String> contentLength = new AtomicReference<>();
    private final AtomicReference<String> transferEncoding = new AtomicReference<>();
    private final Set<Integer> clientPorts = ConcurrentHashMap.newKeySet();
    private final AtomicInteger slowCalls = new AtomicInteger();

    @BeforeEach
    void start() throws IOException {
        server = HttpServer.create(new InetSocketAddress("127.0.0.1", 0), 0);
        server.createContext("/v1/locate", exchange -> {
            received.set(exchange.getRequestBody().readAllBytes());
            frameHeader.set(exchange.getRequestHeaders().getFirst("X-Lumipose-Frame"));
            encoding.set(exchange.getRequestHeaders().getFirst("Content-Encoding"));
            query.set(exchange.getRequestURI().getRawQuery());
            contentLength.set(exchange.getRequestHeaders().getFirst("Content-Length"));
            transferEncoding.set(exchange.getRequestHeaders().getFirst("Transfer-Encoding"));
            clientPorts.add(exchange.getRemoteAddress().getPort());
            boolean keyOk = "k".equals(exchange.getRequestHeaders().getFirst("X-API-Key"));
            byte[] body = (keyOk ? LumiposeClientTest.OK
                    : "{\"error\": \"unauthorized\", \"field\": null, \"message\": \"wrong API key\"}")
                    .getBytes(StandardCharsets.UTF_8);
            exchange.sendResponseHeaders(keyOk ? 200 : 401, body.length);
            try (OutputStream out = exchange.getResponseBody()) {
                out.write(body);
            }
        });
        server.createContext("/slow/v1/locate", exchange -> {
            slowCalls.incrementAndGet();
            exchange.getRequestBody().readAllBytes();
            answerLate();
            exchange.sendResponseHeaders(500, -1);
            exchange.close();
        });
        server.createContext("/slow/v1/samples", exchange -> {
            slowCalls.incrementAndGet();
            exchange.getRequestBody().readAllBytes();
            answerLate();
            byte[] body = LumiposeClientTest.SAMPLE.getBytes(StandardCharsets.UTF_8);
            exchange.sendResponseHeaders(201, body.length);
            try (OutputStream out = exchange.getResponseBody()) {
                out.write(body);
            }
        });
        server.setExecutor(Executors.newCachedThreadPool());
        server.start();
    }

    /** A slow server: 1.5 s before it answers. */
    private static void answerLate() {
        try {
            Thread.sleep(1500);
        } catch (InterruptedException e) {
            Thread.currentThread().interrupt();
        }
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

    /**
     * The body is streamed with its fixed length; the JDK then drops a 401's body (HttpRetryException,
     * Android's HttpURLConnection does not), so the status alone must make the same exception.
     */
    @Test
    void aWrongKeyIsA401WithItsCodeAfterAStreamedUpload() {
        FrameMeta meta = FrameMeta.builder(2, 2).camera(new Intrinsics(5, 5, 0.5, 0.5, null, null, null, null)).build();
        ServerRejectedException e = assertThrows(ServerRejectedException.class,
                () -> client("wrong").locate(new byte[4], meta));
        assertEquals(401, e.status);
        assertEquals("unauthorized", e.code);
    }

    private String url() {
        return "http://127.0.0.1:" + server.getAddress().getPort();
    }

    private static FrameMeta meta(int w, int h) {
        return FrameMeta.builder(w, h).camera(new Intrinsics(50, 50, w / 2.0, h / 2.0, null, null, null, null)).build();
    }

    @Test
    void liveFramesGoRawWithTheirLengthTheMapNameAndOneKeptAliveConnection() throws Exception {
        LumiposeClient live = LumiposeClient.create(ClientConfig.live(url(), "k", "phone-1", "office 2/b"));
        byte[] luma = new byte[64 * 48];
        for (int i = 0; i < 5; i++) {
            assertTrue(live.locate(luma, meta(64, 48)).ok);
            assertEquals(null, encoding.get(), "no gzip for live frames");
            assertEquals(String.valueOf(luma.length), contentLength.get(), "fixed-length body");
            assertEquals(null, transferEncoding.get(), "not chunked");
            assertEquals("map=office+2%2Fb", query.get());
        }
        assertEquals(1, clientPorts.size(), "one connection for all five frames: " + clientPorts);
    }

    @Test
    void aLiveFrameIsTriedOnceWithAShortReadTimeout() {
        ClientConfig live = ClientConfig.live(url() + "/slow", null, null, null);
        assertEquals(1, live.retry.maxAttempts);
        assertEquals(ClientConfig.LIVE_READ_TIMEOUT_MS, live.readTimeoutMs);
        assertFalse(live.gzip);
        LumiposeClient c = LumiposeClient.create(live.withTimeouts(2000, 300));
        long start = System.nanoTime();
        assertThrows(IOException.class, () -> c.locate(new byte[4], meta(2, 2)));
        assertTrue(System.nanoTime() - start < 1_400_000_000L, "gave up at the read timeout");
        assertEquals(1, slowCalls.get());
    }

    /** A sample is stored once even when it is answered after the client's read timeout: its call waits longer. */
    @Test
    void aSampleWaitsForItsSlowAnswerOnce() throws Exception {
        ClientConfig config = new ClientConfig(url() + "/slow", null, null, false, RetryPolicy.defaults())
                .withTimeouts(2000, 300, 5000);
        assertEquals("abc", LumiposeClient.create(config).storeSample("3,-4", new byte[4], meta(2, 2)).id);
        assertEquals(1, slowCalls.get());
    }

    @Test
    void theBodyIsASliceOfTheCallersArray() throws Exception {
        byte[] big = new byte[100];
        for (int i = 0; i < big.length; i++) {
            big[i] = (byte) i;
        }
        HttpCall call = new HttpCall("POST", url() + "/v1/locate", java.util.Collections.singletonMap("X-API-Key", "k"),
                big, 10, 20);
        assertEquals(200, new UrlConnectionTransport(2000, 2000).send(call).status);
        assertArrayEquals(java.util.Arrays.copyOfRange(big, 10, 30), received.get());
        assertEquals("20", contentLength.get());
    }
}
