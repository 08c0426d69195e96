package io.lumipose.client.net;

/** How often and how patiently to retry: exponential back-off between attempts, capped. */
public final class RetryPolicy {
    public final int maxAttempts;
    public final long initialBackoffMs;
    public final double multiplier;
    public final long maxBackoffMs;

    public RetryPolicy(int maxAttempts, long initialBackoffMs, double multiplier, long maxBackoffMs) {
        if (maxAttempts < 1) {
            throw new IllegalArgumentException("maxAttempts must be >= 1, got " + maxAttempts);
        }
        if (initialBackoffMs < 0 || maxBackoffMs < initialBackoffMs || !(multiplier >= 1)) {
            throw new IllegalArgumentException("back-off needs 0 <= initial <= max and multiplier >= 1");
        }
        this.maxAttempts = maxAttempts;
        this.initialBackoffMs = initialBackoffMs;
        this.multiplier = multiplier;
        this.maxBackoffMs = maxBackoffMs;
    }

    /** Three attempts, 200 ms then 400 ms apart: short, since a newer frame soon replaces this one. */
    public static RetryPolicy defaults() {
        return new RetryPolicy(3, 200, 2.0, 2000);
    }

    /** Wait before retry number {@code retry} (1 = the first retry). */
    public long backoffMs(int retry) {
        double ms = initialBackoffMs * Math.pow(multiplier, retry - 1);
        return (long) Math.min(ms, maxBackoffMs);
    }

    /** Statuses worth another try: the server or a proxy was busy or briefly down. */
    public static boolean retryable(int status) {
        return status == 408 || status == 429 || status == 502 || status == 503 || status == 504;
    }
}
