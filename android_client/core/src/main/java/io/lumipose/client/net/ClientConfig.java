package io.lumipose.client.net;

/** Where the server is and how to talk to it (the app's settings screen fills this). */
public final class ClientConfig {
    /** A live frame is stale within a second or two: wait this long for its answer, once. */
    public static final int LIVE_READ_TIMEOUT_MS = 3000;
    public static final int CONNECT_TIMEOUT_MS = 3000;
    /** Map fetches and other reads: worth waiting for, and retried. */
    public static final int PATIENT_READ_TIMEOUT_MS = 15000;
    /**
     * Requests that store (a sample, a survey's map) go once and wait this long: a retry after a read
     * timeout would store a second sample, or run a survey of minutes again behind the first, while
     * the app reports a failure for what the server did (a survey of 200 photos takes a minute or more).
     */
    public static final int STORING_READ_TIMEOUT_MS = 300000;

    public final String baseUrl;
    /** Sent as X-API-Key when set; null for a server without a key. */
    public final String apiKey;
    /** Sent as X-Lumipose-Device when set. */
    public final String deviceId;
    /** Every frame body gzip-compressed. */
    public final boolean gzip;
    /**
     * Pose frames' windows gzip-compressed at the fastest level: a quarter or more of such a window
     * is the panel's clipped plateau, so deflate shrinks it 5-7 times for a few milliseconds (ID
     * frames' stripes and whole planes do not pay; docs/android.md, "Benchmark").
     */
    public final boolean gzipPoseWindows;
    public final RetryPolicy retry;
    /** Sent as {@code ?map=} with every frame, so the server locates in the map the app draws; null: its active map. */
    public final String mapName;
    public final int connectTimeoutMs;
    public final int readTimeoutMs;
    /** The read timeout of the requests that store, sent once ({@link #STORING_READ_TIMEOUT_MS}). */
    public final int storingReadTimeoutMs;

    public ClientConfig(String baseUrl, String apiKey, String deviceId, boolean gzip, RetryPolicy retry) {
        this(baseUrl, apiKey, deviceId, gzip, false, retry, null, CONNECT_TIMEOUT_MS, PATIENT_READ_TIMEOUT_MS,
                STORING_READ_TIMEOUT_MS);
    }

    private ClientConfig(String baseUrl, String apiKey, String deviceId, boolean gzip, boolean gzipPoseWindows,
                         RetryPolicy retry, String mapName, int connectTimeoutMs, int readTimeoutMs,
                         int storingReadTimeoutMs) {
        if (baseUrl == null || !(baseUrl.startsWith("http://") || baseUrl.startsWith("https://"))) {
            throw new IllegalArgumentException("server URL must start with http:// or https://, got '" + baseUrl + "'");
        }
        if (connectTimeoutMs <= 0 || readTimeoutMs <= 0 || storingReadTimeoutMs <= 0) {
            throw new IllegalArgumentException("timeouts must be > 0 ms");
        }
        String trimmed = baseUrl.trim();
        while (trimmed.endsWith("/")) {
            trimmed = trimmed.substring(0, trimmed.length() - 1);
        }
        this.baseUrl = trimmed;
        this.apiKey = blankToNull(apiKey);
        this.deviceId = blankToNull(deviceId);
        this.gzip = gzip;
        this.gzipPoseWindows = gzipPoseWindows;
        this.retry = retry;
        this.mapName = blankToNull(mapName);
        this.connectTimeoutMs = connectTimeoutMs;
        this.readTimeoutMs = readTimeoutMs;
        this.storingReadTimeoutMs = storingReadTimeoutMs;
    }

    /**
     * For live frames: one attempt, a short read timeout (a newer frame replaces a lost one; three
     * attempts of 15 s would hold the uploader for a minute), pose windows gzip-compressed, nothing
     * else (whole planes and ID frames cost more to deflate than they save), and the map the app draws.
     */
    public static ClientConfig live(String baseUrl, String apiKey, String deviceId, String mapName) {
        return new ClientConfig(baseUrl, apiKey, deviceId, false, true, new RetryPolicy(1, 0, 1.0, 0), mapName,
                CONNECT_TIMEOUT_MS, LIVE_READ_TIMEOUT_MS, STORING_READ_TIMEOUT_MS);
    }

    /** The same, with frames located in the map {@code name} (null: the server's active map). */
    public ClientConfig withMap(String name) {
        return new ClientConfig(baseUrl, apiKey, deviceId, gzip, gzipPoseWindows, retry, name, connectTimeoutMs,
                readTimeoutMs, storingReadTimeoutMs);
    }

    public ClientConfig withTimeouts(int connectMs, int readMs) {
        return withTimeouts(connectMs, readMs, storingReadTimeoutMs);
    }

    /** With the read timeout of the requests that store as well. */
    public ClientConfig withTimeouts(int connectMs, int readMs, int storingReadMs) {
        return new ClientConfig(baseUrl, apiKey, deviceId, gzip, gzipPoseWindows, retry, mapName, connectMs, readMs,
                storingReadMs);
    }

    private static String blankToNull(String s) {
        return s == null || s.trim().isEmpty() ? null : s.trim();
    }
}
