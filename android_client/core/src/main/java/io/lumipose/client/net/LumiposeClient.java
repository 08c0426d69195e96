package io.lumipose.client.net;

import java.io.ByteArrayOutputStream;
import java.io.IOException;
import java.io.UnsupportedEncodingException;
import java.net.URLEncoder;
import java.util.LinkedHashMap;
import java.util.Map;
import java.util.zip.Deflater;
import java.util.zip.GZIPOutputStream;

import org.json.JSONObject;

import io.lumipose.client.frame.FrameMeta;
import io.lumipose.client.json.Json;
import io.lumipose.client.map.RoomMap;

/**
 * The client side of {@code lumipose serve}'s HTTP API: raw frame bytes in the body, the frame JSON
 * in the {@code X-Lumipose-Frame} header, optionally gzip-compressed; retries with back-off on
 * network errors and busy statuses; any other 4xx/5xx becomes a {@link ServerRejectedException}.
 * Requests that store (a sample, a survey) are sent once and given a long read timeout
 * ({@link ClientConfig#storingReadTimeoutMs}): a retry would store twice, or run a long survey again.
 */
public final class LumiposeClient implements FrameUploader {
    private final ClientConfig config;
    private final HttpTransport transport;
    private final Sleeper sleeper;

    public LumiposeClient(ClientConfig config, HttpTransport transport, Sleeper sleeper) {
        this.config = config;
        this.transport = transport;
        this.sleeper = sleeper;
    }

    /** A client over HttpURLConnection with the config's timeouts and real sleeps. */
    public static LumiposeClient create(ClientConfig config) {
        return new LumiposeClient(config, new UrlConnectionTransport(config.connectTimeoutMs, config.readTimeoutMs),
                Sleeper.REAL);
    }

    @Override
    public LocateResult upload(byte[] luma, FrameMeta meta) throws IOException, ServerRejectedException,
            InterruptedException {
        return locate(luma, meta);
    }

    /**
     * POST /v1/locate (with {@code ?map=} when the config names one). A refusal (no beacon, ...) is a
     * result with {@code ok == false}, not an exception.
     */
    public LocateResult locate(byte[] luma, FrameMeta meta) throws IOException, ServerRejectedException,
            InterruptedException {
        String map = config.mapName == null ? "" : "?map=" + urlEncode(config.mapName);
        String url = config.baseUrl + "/v1/locate" + map;
        HttpReply reply = call(frameCall(url, luma, meta), 200);
        return LocateResult.fromJson(reply.text());
    }

    /**
     * POST /v1/samples?label=...: stores the frame with its label (a test-bench cell, "3,-4"). Sent once
     * (see {@link #postJsonOnce}): a lost answer is an IOException, the sample perhaps stored.
     */
    public StoredSample storeSample(String label, byte[] luma, FrameMeta meta) throws IOException,
            ServerRejectedException, InterruptedException {
        if (label == null || label.trim().isEmpty()) {
            throw new IllegalArgumentException("label must not be empty");
        }
        HttpReply reply = callOnce(frameCall(config.baseUrl + "/v1/samples?label=" + urlEncode(label), luma, meta),
                201);
        return StoredSample.fromJson(reply.text());
    }

    /**
     * POST a frame as {@link #locate} sends it (Y8 body, frame JSON header) to another route, with
     * extra headers ({@code X-Lumipose-Board}, say); returns the 2xx answer's body. The screens'
     * sessions (calibration, survey) parse it into their own contract types.
     *
     * @param pathAndQuery from the server's root, e.g. {@code /v1/calibrations/views?name=p1} (encode with
     *                     {@link #urlEncode})
     */
    public String postFrame(String pathAndQuery, Map<String, String> headers, byte[] luma, FrameMeta meta)
            throws IOException, ServerRejectedException, InterruptedException {
        return call(frameCall(config.baseUrl + pathAndQuery, luma, meta, headers), ANY_SUCCESS).text();
    }

    /**
     * A JSON request ({@code body} null: none) to a route of the server; returns the 2xx answer's
     * body. The API key goes with it (PUT /v1/profiles and PUT /v1/maps/active need it).
     */
    public String sendJson(String method, String pathAndQuery, JSONObject body) throws IOException,
            ServerRejectedException, InterruptedException {
        Map<String, String> headers = baseHeaders();
        byte[] bytes = null;
        if (body != null) {
            headers.put("Content-Type", "application/json");
            bytes = body.toString().getBytes("UTF-8");
        }
        return call(new HttpCall(method, config.baseUrl + pathAndQuery, headers, bytes), ANY_SUCCESS).text();
    }

    /**
     * A JSON POST that stores or computes for long (a survey with {@code store: true}): sent once, its
     * answer awaited up to {@link ClientConfig#storingReadTimeoutMs}, since a retry after a read timeout
     * would run it a second time while the first still runs (and store twice). A lost answer is an
     * IOException saying it was sent once: the server may have done it.
     */
    public String postJsonOnce(String pathAndQuery, JSONObject body) throws IOException, ServerRejectedException,
            InterruptedException {
        Map<String, String> headers = baseHeaders();
        headers.put("Content-Type", "application/json");
        HttpCall c = new HttpCall("POST", config.baseUrl + pathAndQuery, headers, body.toString().getBytes("UTF-8"));
        return callOnce(c, ANY_SUCCESS).text();
    }

    /** PUT /v1/maps/active: the server locates in map {@code name} when a frame names none. */
    public void setActiveMap(String name) throws IOException, ServerRejectedException, InterruptedException {
        JSONObject body = new JSONObject();
        Json.put(body, "name", name);
        sendJson("PUT", "/v1/maps/active", body);
    }

    /** GET /v1/maps/{name}: the beacon map to draw. */
    public RoomMap fetchMap(String name) throws IOException, ServerRejectedException, InterruptedException {
        HttpReply reply = call(new HttpCall("GET", config.baseUrl + "/v1/maps/" + urlEncode(name),
                baseHeaders(), null), 200);
        return RoomMap.fromJson(reply.text());
    }

    /** GET /healthz once, no retries: true when the server answers 200. */
    public boolean healthy() {
        try {
            return transport.send(new HttpCall("GET", config.baseUrl + "/healthz", baseHeaders(), null)).status == 200;
        } catch (IOException e) {
            return false;
        }
    }

    HttpCall frameCall(String url, byte[] luma, FrameMeta meta) throws IOException {
        return frameCall(url, luma, meta, new LinkedHashMap<String, String>());
    }

    private HttpCall frameCall(String url, byte[] luma, FrameMeta meta, Map<String, String> extraHeaders)
            throws IOException {
        if (!"Y8".equals(meta.format)) {
            throw new IllegalArgumentException("format: the client uploads Y8 frames, got " + meta.format);
        }
        if (luma.length != meta.frameBytes()) {
            throw new IllegalArgumentException("frame bytes: " + luma.length + " given, row_stride * height = "
                    + meta.frameBytes());
        }
        Map<String, String> headers = baseHeaders();
        headers.put("Content-Type", "application/octet-stream");
        headers.put("X-Lumipose-Frame", meta.toHeaderValue());
        headers.putAll(extraHeaders);
        byte[] body = luma;
        boolean poseWindow = meta.isWindow() && !"id".equals(meta.frameKind);
        if (config.gzip || config.gzipPoseWindows && poseWindow) {
            headers.put("Content-Encoding", "gzip");
            body = gzip(luma);
        }
        return new HttpCall("POST", url, headers, body);
    }

    private Map<String, String> baseHeaders() {
        Map<String, String> h = new LinkedHashMap<String, String>();
        h.put("Accept", "application/json");
        if (config.apiKey != null) {
            h.put("X-API-Key", config.apiKey);
        }
        if (config.deviceId != null) {
            h.put("X-Lumipose-Device", config.deviceId);
        }
        return h;
    }

    /** {@link #call}'s expected status for "any 2xx". */
    private static final int ANY_SUCCESS = -1;

    private HttpReply call(HttpCall c, int expectedStatus) throws IOException, ServerRejectedException,
            InterruptedException {
        return call(c, expectedStatus, config.retry.maxAttempts);
    }

    /** One attempt with the long read timeout of the requests that store. */
    private HttpReply callOnce(HttpCall c, int expectedStatus) throws IOException, ServerRejectedException,
            InterruptedException {
        try {
            return call(c.withReadTimeout(config.storingReadTimeoutMs), expectedStatus, 1);
        } catch (IOException e) {
            throw new IOException(e.getMessage() + " (sent once: the server may have stored it all the same)",
                    e.getCause());
        }
    }

    private HttpReply call(HttpCall c, int expectedStatus, int maxAttempts) throws IOException,
            ServerRejectedException, InterruptedException {
        IOException lastError = null;
        HttpReply lastReply = null;
        for (int attempt = 1; attempt <= maxAttempts; attempt++) {
            if (attempt > 1) {
                sleeper.sleep(config.retry.backoffMs(attempt - 1));
            }
            try {
                lastReply = transport.send(c);
                lastError = null;
            } catch (IOException e) {
                lastError = e;
                continue;
            }
            if (lastReply.status == expectedStatus
                    || expectedStatus == ANY_SUCCESS && lastReply.status >= 200 && lastReply.status < 300) {
                return lastReply;
            }
            if (!RetryPolicy.retryable(lastReply.status)) {
                break;
            }
        }
        if (lastError != null) {
            String tries = maxAttempts == 1 ? "" : " after " + maxAttempts + " attempts";
            throw new IOException("no answer from " + c.url + tries + ": " + lastError.getMessage(), lastError);
        }
        throw ServerRejectedException.fromBody(lastReply.status, lastReply.text());
    }

    /** A frame body as the client compresses it: gzip at deflate's fastest level (a frame is stale in a second). */
    public static byte[] gzip(byte[] data) throws IOException {
        ByteArrayOutputStream out = new ByteArrayOutputStream(data.length / 4 + 64);
        GZIPOutputStream z = new GZIPOutputStream(out) {
            {
                def.setLevel(Deflater.BEST_SPEED);
            }
        };
        try {
            z.write(data);
        } finally {
            z.close();
        }
        return out.toByteArray();
    }

    /** A path segment or query value, URL-encoded (UTF-8). */
    public static String urlEncode(String s) {
        try {
            return URLEncoder.encode(s, "UTF-8");
        } catch (UnsupportedEncodingException e) {
            throw new IllegalStateException("UTF-8 is always supported", e);
        }
    }
}
