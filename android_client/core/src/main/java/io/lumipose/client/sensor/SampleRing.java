package io.lumipose.client.sensor;

/**
 * Timestamped sensor readings in arrival order, overwriting the oldest; the storage the
 * histories share. Not thread-safe itself: its owner synchronizes.
 *
 * <p>A reading is copied into the row it overwrites (a new row only while the ring fills, or for
 * a reading of another length): at ~300 events a second nothing is allocated per event, and the
 * caller may reuse its array, as Android does SensorEvent.values.
 */
final class SampleRing {
    private final long[] times;
    private final float[][] values;
    private int next;
    private int size;

    SampleRing(int capacity) {
        if (capacity < 2) {
            throw new IllegalArgumentException("capacity must be >= 2, got " + capacity);
        }
        times = new long[capacity];
        values = new float[capacity][];
    }

    void add(long timestampNs, float[] v) {
        times[next] = timestampNs;
        float[] row = values[next];
        if (row == null || row.length != v.length) {
            row = new float[v.length];
            values[next] = row;
        }
        System.arraycopy(v, 0, row, 0, v.length);
        next = (next + 1) % times.length;
        size = Math.min(size + 1, times.length);
    }

    float[] latest() {
        return size == 0 ? null : values[(next - 1 + times.length) % times.length].clone();
    }

    /** Interpolated (or nearest) reading at {@code t}; null when the nearest is farther than maxGapNs. */
    float[] at(long t, long maxGapNs, boolean interpolate) {
        int before = -1;
        int after = -1;
        for (int i = 0; i < size; i++) {
            long ti = times[i];
            if (ti <= t && (before < 0 || ti > times[before])) {
                before = i;
            }
            if (ti >= t && (after < 0 || ti < times[after])) {
                after = i;
            }
        }
        long gapBefore = before < 0 ? Long.MAX_VALUE : t - times[before];
        long gapAfter = after < 0 ? Long.MAX_VALUE : times[after] - t;
        if (Math.min(gapBefore, gapAfter) > maxGapNs) {
            return null;
        }
        if (!interpolate || gapBefore == 0 || gapAfter == 0 || gapBefore > maxGapNs
                || gapAfter > maxGapNs) {
            return values[gapBefore <= gapAfter ? before : after].clone();
        }
        double w = (double) gapBefore / (gapBefore + gapAfter);
        float[] a = values[before];
        float[] b = values[after];
        float[] out = new float[a.length];
        for (int i = 0; i < a.length; i++) {
            out[i] = (float) (a[i] + w * (b[i] - a[i]));
        }
        return out;
    }

    /**
     * The mean of the readings stamped within [t0, t1] (a plain mean: a sensor's readings come
     * evenly spaced); with none inside, the reading nearest the window; null when that one lies
     * farther than maxGapNs from it.
     */
    float[] mean(long t0, long t1, long maxGapNs) {
        double[] sum = null;
        int inside = 0;
        int nearest = -1;
        long nearestGap = Long.MAX_VALUE;
        for (int i = 0; i < size; i++) {
            long gap = times[i] < t0 ? t0 - times[i] : times[i] > t1 ? times[i] - t1 : 0;
            if (gap < nearestGap) {
                nearest = i;
                nearestGap = gap;
            }
            if (gap == 0) {
                sum = sum == null ? new double[values[i].length] : sum;
                for (int k = 0; k < sum.length; k++) {
                    sum[k] += values[i][k];
                }
                inside++;
            }
        }
        if (inside == 0) {
            return nearest >= 0 && nearestGap <= maxGapNs ? values[nearest].clone() : null;
        }
        float[] out = new float[sum.length];
        for (int k = 0; k < out.length; k++) {
            out[k] = (float) (sum[k] / inside);
        }
        return out;
    }

    /** A reading farther than this from the time asked for is not the reading then. */
    static long requireMaxGap(long maxGapNs) {
        if (maxGapNs <= 0) {
            throw new IllegalArgumentException("maxGapNs must be > 0, got " + maxGapNs);
        }
        return maxGapNs;
    }

    static float[] requireLength(float[] v, int length, String what) {
        if (v == null || v.length < length) {
            throw new IllegalArgumentException(what + " needs " + length + " values");
        }
        return v;
    }
}
