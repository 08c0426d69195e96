package io.lumipose.client.sensor;

/**
 * The last few seconds of gyroscope readings (TYPE_GYROSCOPE: rad/s about the device's x, y, z,
 * counter-clockwise positive), stamped with the sensor events' timestamps, so each frame gets
 * the mean rate over its own readout: the server undoes the rolling shutter's skew with it.
 * Written by the sensor thread, read by the camera thread: every method is synchronized.
 */
public final class GyroHistory {
    /** About 2 s at the app's 200 Hz, 1 s at 500 Hz. */
    public static final int DEFAULT_CAPACITY = 400;
    /**
     * A window without a reading of its own takes the nearest one this close: hand tremor changes
     * the rate within tens of ms, so an older reading is not the frame's.
     */
    public static final long DEFAULT_MAX_GAP_NS = 20_000_000L;

    private final SampleRing rates;
    private final long maxGapNs;

    public GyroHistory() {
        this(DEFAULT_CAPACITY, DEFAULT_MAX_GAP_NS);
    }

    public GyroHistory(int capacity, long maxGapNs) {
        rates = new SampleRing(capacity);
        this.maxGapNs = SampleRing.requireMaxGap(maxGapNs);
    }

    /** @param rateDevice TYPE_GYROSCOPE [x, y, z], device frame, rad/s */
    public synchronized void add(long timestampNs, float[] rateDevice) {
        rates.add(timestampNs, SampleRing.requireLength(rateDevice, 3, "rotation rate"));
    }

    /**
     * The mean rate (device frame, rad/s) over [t0Ns, t1Ns] from the readings inside it, else the
     * nearest reading within the max gap; null when there is none.
     */
    public synchronized float[] meanOver(long t0Ns, long t1Ns) {
        if (t1Ns < t0Ns) {
            throw new IllegalArgumentException("window ends before it starts: [" + t0Ns + ", " + t1Ns + "]");
        }
        return rates.mean(t0Ns, t1Ns, maxGapNs);
    }

    /**
     * The mean rate over a frame's readout, null when the camera's timestamps are not REALTIME:
     * then they cannot be matched to the readings, and the latest reading is no frame's rate.
     */
    public float[] forFrame(long readoutStartNs, long readoutEndNs, boolean timestampsRealtime) {
        return timestampsRealtime ? meanOver(readoutStartNs, readoutEndNs) : null;
    }
}
