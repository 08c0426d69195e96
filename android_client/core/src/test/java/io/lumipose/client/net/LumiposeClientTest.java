package io.lumipose.client.net;

import static org.junit.jupiter.api.Assertions.assertArrayEquals;
import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertFalse;
import static org.junit.jupiter.api.Assertions.assertThrows;
import static org.junit.jupiter.api.Assertions.assertTrue;

import java.io.ByteArrayInputStream;
import java.io.IOException;
import java.util.ArrayList;
import java.util.List;
import java.util.zip.GZIPInputStream;

import org.json.JSONObject;
import org.junit.jupiter.api.Test;

import io.lumipose.client.camera.Intrinsics;
import io.lumipose.client.frame.FrameMeta;

class LumiposeClientTest {
    static final String OK = "{\"schema\": \"lumipose.result/1\", \"ok\": true, \"position_m\": [0.1, 0.2, 0.0],"
            + " \"beacon_id\": 0, \"gravity_used\": true}";
    static final String SAMPLE = "{\"id\": \"abc\", \"label\": \"3,-4\", \"result\": " + OK + "}";
    private static final FrameMeta META = FrameMeta.builder(4, 3)
            .camera(new Intrinsics(5, 5, 1.5, 1, null, null, null, "fake")).exposureS(0.01).build();
    private static final byte[] LUMA = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12};

    private final List<Long> sleeps = new ArrayList<>();
    private final Sleeper recorder = sleeps::add;

    private LumiposeClient client(FakeTransport t, boolean gzip, String key) {
        return new LumiposeClient(new ClientConfig("http://127.0.0.1:8765/", key, "phone-1", gzip,
                new RetryPolicy(3, 200, 2.0, 1000)), t, recorder);
    }

    static byte[] gunzip(byte[] z) throws IOException {
        try (GZIPInputStream in = new GZIPInputStream(new ByteArrayInputStream(z))) {
            return in.readAllBytes();
        }
    }

    @Test
    void locateSendsTheFrameAsTheApiAsks() throws Exception {
        FakeTransport t = new FakeTransport().reply(200, OK);
        LocateResult r = client(t, true, "secret").locate(LUMA, META);
        assertTrue(r.ok);
        assertArrayEquals(new double[] {0.1, 0.2, 0.0}, r.positionM(), 0);
        HttpCall c = t.calls.get(0);
        assertEquals("POST", c.method);
        assertEquals("http://127.0.0.1:8765/v1/locate", c.url);
        assertEquals("application/octet-stream", c.headers.get("Content-Type"));
        assertEquals("gzip", c.headers.get("Content-Encoding"));
        assertEquals("secret", c.headers.get("X-API-Key"));
        assertEquals("phone-1", c.headers.get("X-Lumipose-Device"));
        assertArrayEquals(LUMA, gunzip(c.body()));
        JSONObject sent = new JSONObject(c.headers.get("X-Lumipose-Frame"));
        assertEquals(4, sent.getInt("width"));
        assertEquals(0.01, sent.getDouble("exposure_s"));
    }

    @Test
    void withoutGzipOrKeyTheBodyIsRawAndNoKeyIsSent() throws Exception {
        FakeTransport t = new FakeTransport().reply(200, OK);
        client(t, false, "  ").locate(LUMA, META);
        HttpCall c = t.calls.get(0);
        assertArrayEquals(LUMA, c.body());
        assertFalse(c.headers.containsKey("Content-Encoding"));
        assertFalse(c.headers.containsKey("X-API-Key"));
    }

    @Test
    void refusalIsAResultNotAnError() throws Exception {
        FakeTransport t = new FakeTransport().reply(200,
                "{\"ok\": false, \"reason\": \"no_beacon\", \"message\": \"nothing bright\"}");
        LocateResult r = client(t, true, null).locate(LUMA, META);
        assertFalse(r.ok);
        assertEquals("no_beacon", r.reason);
    }

    @Test
    void networkErrorsAreRetriedWithGrowingBackoff() throws Exception {
        FakeTransport t = new FakeTransport().fail("refused").fail("reset").reply(200, OK);
        assertTrue(client(t, true, null).locate(LUMA, META).ok);
        assertEquals(3, t.calls.size());
        assertEquals(List.of(200L, 400L), sleeps);
    }

    @Test
    void busyServerIsRetriedThenItsErrorReported() throws Exception {
        FakeTransport t = new FakeTransport().reply(503, "{}").reply(200, OK);
        assertTrue(client(t, true, null).locate(LUMA, META).ok);
        assertEquals(2, t.calls.size());

        FakeTransport busy = new FakeTransport().reply(503, "").reply(503, "").reply(503,
                "{\"error\": \"busy\", \"field\": null, \"message\": \"try later\"}");
        ServerRejectedException e = assertThrows(ServerRejectedException.class,
                () -> client(busy, true, null).locate(LUMA, META));
        assertEquals(503, e.status);
        assertEquals("busy", e.code);
    }

    @Test
    void clientErrorsAreNotRetried() {
        FakeTransport t = new FakeTransport().reply(422,
                "{\"error\": \"invalid\", \"field\": \"camera.fx\", \"message\": \"must be > 0\"}");
        ServerRejectedException e = assertThrows(ServerRejectedException.class,
                () -> client(t, true, null).locate(LUMA, META));
        assertEquals(1, t.calls.size());
        assertEquals("camera.fx", e.field);
        assertTrue(sleeps.isEmpty());
    }

    @Test
    void aNonContractErrorBodyStillReadsWell() {
        FakeTransport t = new FakeTransport().reply(404, "<html>Not Found</html>");
        ServerRejectedException e = assertThrows(ServerRejectedException.class,
                () -> client(t, true, null).locate(LUMA, META));
        assertEquals(404, e.status);
        assertEquals("http_404", e.code);
        assertTrue(e.getMessage().contains("Not Found"), e.getMessage());
    }

    @Test
    void givesUpAfterTheLastAttempt() {
        FakeTransport t = new FakeTransport().fail("a").fail("b").fail("c");
        IOException e = assertThrows(IOException.class, () -> client(t, true, null).locate(LUMA, META));
        assertTrue(e.getMessage().contains("3 attempts"), e.getMessage());
        assertEquals(3, t.calls.size());
    }

    @Test
    void wrongByteCountIsRefusedBeforeSending() {
        FakeTransport t = new FakeTransport();
        IllegalArgumentException e = assertThrows(IllegalArgumentException.class,
                () -> client(t, true, null).locate(new byte[11], META));
        assertTrue(e.getMessage().contains("row_stride * height = 12"), e.getMessage());
        assertTrue(t.calls.isEmpty());
    }

    @Test
    void sampleIsStoredWithItsCellLabel() throws Exception {
        FakeTransport t = new FakeTransport().reply(201, SAMPLE);
        StoredSample s = client(t, true, "k").storeSample("3,-4", LUMA, META);
        assertEquals("abc", s.id);
        assertEquals("3,-4", s.label);
        assertTrue(s.result.ok);
        assertEquals("http://127.0.0.1:8765/v1/samples?label=3%2C-4", t.calls.get(0).url);
        assertThrows(IllegalArgumentException.class, () -> client(t, true, "k").storeSample(" ", LUMA, META));
    }

    /** A sample is stored on arrival: an answer slower than the patient timeout must not store it twice. */
    @Test
    void aSlowSampleAnswerIsAwaitedNotSentAgain() throws Exception {
        long slow = ClientConfig.PATIENT_READ_TIMEOUT_MS + 20000;
        FakeTransport t = new FakeTransport().replyAfter(slow, 201, SAMPLE);
        assertEquals("abc", client(t, false, "k").storeSample("3,-4", LUMA, META).id);
        assertEquals(1, t.calls.size(), "one POST");
        assertEquals(ClientConfig.STORING_READ_TIMEOUT_MS, t.calls.get(0).readTimeoutMs);
        assertTrue(sleeps.isEmpty());
    }

    @Test
    void aLostSampleAnswerIsNotRetriedAndSaysItWasSentOnce() {
        FakeTransport t = new FakeTransport().fail("connection reset").reply(201, SAMPLE);
        IOException e = assertThrows(IOException.class, () -> client(t, false, "k").storeSample("3,-4", LUMA, META));
        assertEquals(1, t.calls.size(), "no second POST: the first may have stored the sample");
        assertTrue(e.getMessage().contains("sent once"), e.getMessage());
        assertTrue(e.getMessage().contains("connection reset"), e.getMessage());
    }

    @Test
    void aPostThatStoresGoesOnceWithTheLongWaitAndReadsStillRetry() throws Exception {
        FakeTransport t = new FakeTransport()
                .replyAfter(ClientConfig.STORING_READ_TIMEOUT_MS + 1, 200, "{}")
                .fail("a").reply(200, "{\"name\": \"m\"}");
        LumiposeClient c = client(t, false, "k");
        IOException e = assertThrows(IOException.class, () -> c.postJsonOnce("/v1/surveys",
                new JSONObject().put("store", true)));
        assertEquals(1, t.calls.size(), "one POST");
        assertTrue(e.getCause() instanceof java.net.SocketTimeoutException, String.valueOf(e.getCause()));
        HttpCall post = t.calls.get(0);
        assertEquals("POST", post.method);
        assertEquals("application/json", post.headers.get("Content-Type"));
        assertEquals("k", post.headers.get("X-API-Key"));
        assertEquals(true, new JSONObject(new String(post.body(), java.nio.charset.StandardCharsets.UTF_8))
                .getBoolean("store"));
        // a GET is retried as before, with the transport's own timeout
        assertEquals("{\"name\": \"m\"}", c.sendJson("GET", "/v1/maps/active", null));
        assertEquals(3, t.calls.size());
        assertEquals(0, t.calls.get(2).readTimeoutMs);
    }

    @Test
    void theStoringWaitIsTheConfigs() throws Exception {
        ClientConfig config = new ClientConfig("http://h", null, null, false, RetryPolicy.defaults())
                .withTimeouts(1000, 2000, 90000);
        assertEquals(90000, config.storingReadTimeoutMs);
        assertEquals(90000, config.withMap("m").storingReadTimeoutMs);
        assertEquals(ClientConfig.STORING_READ_TIMEOUT_MS,
                ClientConfig.live("http://h", null, null, null).storingReadTimeoutMs);
        FakeTransport t = new FakeTransport().reply(201, SAMPLE);
        new LumiposeClient(config, t, recorder).storeSample("a", LUMA, META);
        assertEquals(90000, t.calls.get(0).readTimeoutMs);
        assertThrows(IllegalArgumentException.class, () -> config.withTimeouts(1000, 2000, 0));
    }

    @Test
    void mapIsFetchedByName() throws Exception {
        FakeTransport t = new FakeTransport().reply(200, "{\"schema\": \"lumipose.map/1\", \"name\": \"demo\","
                + " \"beacons\": [{\"id\": 0, \"center_m\": [0, 0, 1], \"side_m\": 0.174}]}");
        assertEquals(1, client(t, true, null).fetchMap("demo").beacons.size());
        assertEquals("GET", t.calls.get(0).method);
        assertEquals("http://127.0.0.1:8765/v1/maps/demo", t.calls.get(0).url);
    }

    @Test
    void configRejectsAUrlWithoutScheme() {
        assertThrows(IllegalArgumentException.class,
                () -> new ClientConfig("192.168.1.2:8765", null, null, true, RetryPolicy.defaults()));
        assertEquals("https://x", new ClientConfig("https://x//", null, null, true, RetryPolicy.defaults()).baseUrl);
    }

    @Test
    void backoffGrowsAndIsCapped() {
        RetryPolicy p = new RetryPolicy(5, 100, 3.0, 500);
        assertEquals(100, p.backoffMs(1));
        assertEquals(300, p.backoffMs(2));
        assertEquals(500, p.backoffMs(3));
        assertThrows(IllegalArgumentException.class, () -> new RetryPolicy(0, 1, 2, 3));
    }

    @Test
    void aLiveFrameGoesOnceRawAndInTheNamedMap() throws Exception {
        ClientConfig live = ClientConfig.live("http://lumi:8000/", "k", "phone", "office 2");
        FakeTransport t = new FakeTransport().reply(200, OK).fail("reset");
        LumiposeClient c = new LumiposeClient(live, t, ms -> {
            throw new AssertionError("no retry, no sleep");
        });
        assertTrue(c.locate(LUMA, META).ok);
        HttpCall call = t.calls.get(0);
        assertEquals("http://lumi:8000/v1/locate?map=office+2", call.url);
        assertFalse(call.headers.containsKey("Content-Encoding"), "no gzip for live frames");
        assertArrayEquals(LUMA, call.body());
        assertThrows(IOException.class, () -> c.locate(LUMA, META));
        assertEquals(2, t.calls.size(), "one attempt for a live frame");
        FakeTransport activeMap = new FakeTransport().reply(200, OK);
        new LumiposeClient(live.withMap(null), activeMap, Sleeper.REAL).locate(LUMA, META);
        assertEquals("http://lumi:8000/v1/locate", activeMap.calls.get(0).url, "no map named: the server's active one");
    }

    @Test
    void aLivePoseWindowGoesGzippedAndAnIdWindowRaw() throws Exception {
        ClientConfig live = ClientConfig.live("http://lumi:8000/", "k", "phone", "office");
        FakeTransport t = new FakeTransport().reply(200, OK).reply(200, OK);
        LumiposeClient c = new LumiposeClient(live, t, Sleeper.REAL);
        FrameMeta window = META.window(0, 0, 4, 3, new double[] {20, 255});
        byte[] plateau = new byte[12];
        java.util.Arrays.fill(plateau, (byte) 255);
        c.locate(plateau, window);
        HttpCall pose = t.calls.get(0);
        assertEquals("gzip", pose.headers.get("Content-Encoding"), "a pose window: mostly clipped plateau");
        assertArrayEquals(plateau, gunzip(pose.body()));
        FrameMeta idWindow = FrameMeta.fromJson(window.toJson().put("frame_kind", "id").put("exposure_s", 1.25e-4)
                .put("rolling_shutter_skew_s", 0.03).put("timestamp_ns", 5));
        c.locate(plateau, idWindow);
        assertFalse(t.calls.get(1).headers.containsKey("Content-Encoding"), "ID frames' stripes do not pay");
        assertArrayEquals(plateau, t.calls.get(1).body());
    }
}
