package io.lumipose.client.sensor;

/**
 * The last few seconds of gravity and rotation readings, stamped with the sensor events'
 * timestamps, so each frame gets the attitude at its own SENSOR_TIMESTAMP rather than whatever
 * arrived last (a phone turning at 90 deg/s moves 9 deg in the 100 ms a result takes to arrive).
 * Written by the sensor thread, read by the camera thread: every method is synchronized.
 *
 * <p>Camera2's SENSOR_INFO_TIMESTAMP_SOURCE says whether frame timestamps share the sensor events'
 * clock: REALTIME does (SystemClock.elapsedRealtimeNanos); UNKNOWN is a monotonic clock of its own,
 * not comparable, so those frames take the latest reading instead ({@link #forFrame}).
 */
public final class GravityHistory implements GravitySource {
    /** Keep about 2 s at 200 Hz. */
    public static final int DEFAULT_CAPACITY = 400;
    /** A reading farther than this from the frame is not its attitude. */
    public static final long DEFAULT_MAX_GAP_NS = 100_000_000L;

    /** A reading: values (3 for gravity, 9 for a rotation matrix) at a sensor timestamp. */
    public static final class Sample {
        public final long timestampNs;
        private final float[] values;

        Sample(long timestampNs, float[] values) {
            this.timestampNs = timestampNs;
            this.values = values.clone();
        }

        public float[] values() {
            return values.clone();
        }
    }

    /** The attitude matched to one frame; either part may be null. */
    public static final class Attitude {
        /** TYPE_GRAVITY [x, y, z] in the device frame, m/s^2, pointing up. */
        public final float[] gravity;
        /** Device-to-East-North-Up rotation, row-major 3x3. */
        public final float[] rotationToEnu;

        Attitude(float[] gravity, float[] rotationToEnu) {
            this.gravity = gravity;
            this.rotationToEnu = rotationToEnu;
        }
    }

    private final SampleRing gravity;
    private final SampleRing rotation;
    private final long maxGapNs;

    public GravityHistory() {
        this(DEFAULT_CAPACITY, DEFAULT_MAX_GAP_NS);
    }

    public GravityHistory(int capacity, long maxGapNs) {
        gravity = new SampleRing(capacity);
        rotation = new SampleRing(capacity);
        this.maxGapNs = SampleRing.requireMaxGap(maxGapNs);
    }

    public synchronized void addGravity(long timestampNs, float[] values) {
        gravity.add(timestampNs, SampleRing.requireLength(values, 3, "gravity"));
    }

    public synchronized void addRotation(long timestampNs, float[] rotationToEnu) {
        rotation.add(timestampNs, SampleRing.requireLength(rotationToEnu, 9, "rotation"));
    }

    /** Gravity at {@code timestampNs}, interpolated between the readings around it; null when none is near. */
    public synchronized float[] gravityAt(long timestampNs) {
        return gravity.at(timestampNs, maxGapNs, true);
    }

    /** The rotation reading nearest {@code timestampNs} (rotations are not averaged linearly); null when none is near. */
    public synchronized float[] rotationAt(long timestampNs) {
        return rotation.at(timestampNs, maxGapNs, false);
    }

    /** The attitude at a sensor-clock timestamp. */
    public synchronized Attitude at(long timestampNs) {
        return new Attitude(gravityAt(timestampNs), rotationAt(timestampNs));
    }

    /**
     * The attitude for a frame: at its SENSOR_TIMESTAMP when the camera's timestamps are realtime
     * (comparable with sensor events), else the latest readings.
     */
    public synchronized Attitude forFrame(long frameTimestampNs, boolean timestampsRealtime) {
        return timestampsRealtime ? at(frameTimestampNs) : new Attitude(latestGravity(), latestRotationToEnu());
    }

    @Override
    public synchronized float[] latestGravity() {
        return gravity.latest();
    }

    @Override
    public synchronized float[] latestRotationToEnu() {
        return rotation.latest();
    }
}
