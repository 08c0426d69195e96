package io.lumipose.client.net;

/** Where the server is and how to talk to it (the app's settings screen fills this). */
public final class ClientConfig {
    public final String baseUrl;
    /** Sent as X-API-Key when set; null for a server without a key. */
    public final String apiKey;
    /** Sent as X-Lumipose-Device when set. */
    public final String deviceId;
    public final boolean gzip;
    public final RetryPolicy retry;

    public ClientConfig(String baseUrl, String apiKey, String deviceId, boolean gzip, RetryPolicy retry) {
        if (baseUrl == null || !(baseUrl.startsWith("http://") || baseUrl.startsWith("https://"))) {
            throw new IllegalArgumentException("server URL must start with http:// or https://, got '" + baseUrl + "'");
        }
        String trimmed = baseUrl.trim();
        while (trimmed.endsWith("/")) {
            trimmed = trimmed.substring(0, trimmed.length() - 1);
        }
        this.baseUrl = trimmed;
        this.apiKey = apiKey == null || apiKey.trim().isEmpty() ? null : apiKey.trim();
        this.deviceId = deviceId == null || deviceId.trim().isEmpty() ? null : deviceId.trim();
        this.gzip = gzip;
        this.retry = retry;
    }
}
