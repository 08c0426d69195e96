package io.lumipose.client.sensor;

/**
 * Gravity from the accelerometer on phones without a TYPE_GRAVITY sensor: a first-order low-pass
 * filter keeps the slow part (gravity) and removes the hand's shake. The filter's weight follows the
 * events' own spacing, so the time constant holds at any sampling rate. Not thread-safe: one
 * sensor thread feeds it.
 */
public final class LowPassGravity {
    /** Long enough to smooth a hand's tremor (8-12 Hz), short enough to follow a turn of the wrist. */
    public static final long DEFAULT_TIME_CONSTANT_NS = 200_000_000L;
    /** A gap longer than this (sensor paused) restarts the filter instead of averaging across it. */
    private static final long RESTART_GAP_NS = 1_000_000_000L;

    private final long timeConstantNs;
    private float[] state;
    private long lastNs;

    public LowPassGravity() {
        this(DEFAULT_TIME_CONSTANT_NS);
    }

    public LowPassGravity(long timeConstantNs) {
        if (timeConstantNs <= 0) {
            throw new IllegalArgumentException("time constant must be > 0 ns, got " + timeConstantNs);
        }
        this.timeConstantNs = timeConstantNs;
    }

    /** Feeds one accelerometer event [x, y, z] m/s^2 and returns the filtered gravity (a new array). */
    public float[] update(long timestampNs, float[] acceleration) {
        if (acceleration == null || acceleration.length < 3) {
            throw new IllegalArgumentException("acceleration needs 3 values [x, y, z]");
        }
        long dt = timestampNs - lastNs;
        if (state == null || dt < 0 || dt > RESTART_GAP_NS) {
            state = new float[] {acceleration[0], acceleration[1], acceleration[2]};
        } else {
            double weight = (double) dt / (timeConstantNs + dt);
            for (int i = 0; i < 3; i++) {
                state[i] += (float) (weight * (acceleration[i] - state[i]));
            }
        }
        lastNs = timestampNs;
        return state.clone();
    }
}
