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
    private final float[] state = new float[3];
    /** False before the first reading, which starts the filter. */
    private boolean started;
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
        return update(timestampNs, acceleration, new float[3]);
    }

    /**
     * The same into {@code out} (3 values), which it returns: the sensor thread's one buffer, so
     * that an event allocates nothing.
     */
    public float[] update(long timestampNs, float[] acceleration, float[] out) {
        if (out == null || out.length < 3) {
            throw new IllegalArgumentException("out needs 3 values");
        }
        if (acceleration == null || acceleration.length < 3) {
            throw new IllegalArgumentException("acceleration needs 3 values [x, y, z]");
        }
        long dt = timestampNs - lastNs;
        if (!started || dt < 0 || dt > RESTART_GAP_NS) {
            System.arraycopy(acceleration, 0, state, 0, 3);
            started = true;
        } else {
            double weight = (double) dt / (timeConstantNs + dt);
            for (int i = 0; i < 3; i++) {
                state[i] += (float) (weight * (acceleration[i] - state[i]));
            }
        }
        lastNs = timestampNs;
        System.arraycopy(state, 0, out, 0, 3);
        return out;
    }
}
