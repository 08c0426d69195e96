package io.lumipose.client.contract;

import java.util.regex.Pattern;

import io.lumipose.client.json.ContractException;

/**
 * The physical range of every number of the contract (docs/contract.md, "Ranges"; the reasons are
 * beside each bound in shared_schemas/models.py). The app refuses a frame the server would refuse,
 * naming the field, instead of sending it. {@code ContractRangesTest} checks every bound here against
 * the exported JSON Schemas (shared_schemas/json/), so the two cannot drift apart.
 */
public final class ContractRanges {
    private ContractRanges() {
    }

    /** A closed interval [min, max] of a number of the contract. */
    public static final class Range {
        public final double min;
        public final double max;

        Range(double min, double max) {
            this.min = min;
            this.max = max;
        }

        public boolean contains(double v) {
            return v >= min && v <= max; // false for NaN
        }

        /** @throws ContractException naming {@code field} when {@code v} is outside [min, max] or not finite */
        public double check(String field, double v) {
            if (!contains(v)) {
                throw new ContractException(field, "must be within [" + format(min) + ", " + format(max) + "], got " + v);
            }
            return v;
        }

        /** {@link #check} of an optional number; null passes. */
        public Double check(String field, Double v) {
            return v == null ? null : check(field, v.doubleValue());
        }

        /** {@link #check} of every item, naming {@code field[i]}. */
        public double[] checkEach(String field, double[] values) {
            if (values != null) {
                for (int i = 0; i < values.length; i++) {
                    check(field + "[" + i + "]", values[i]);
                }
            }
            return values;
        }

        private static String format(double v) {
            return v == Math.rint(v) && Math.abs(v) < 1e15 ? Long.toString((long) v) : Double.toString(v);
        }
    }

    /** width, height, crop.full_width, crop.full_height: a 200 MP sensor is 16 320 x 12 240. */
    public static final Range SIDE_PX = new Range(1, 100_000);
    /** crop.x, crop.y. */
    public static final Range CROP_OFFSET_PX = new Range(0, 100_000);
    /** An 8-bit luma level (crop.levels_dn). */
    public static final Range GREY_LEVEL_DN = new Range(0, 255);
    /** row_stride, bytes: the widest frame with as much padding again. */
    public static final Range ROW_STRIDE = new Range(1, 200_000);
    /** camera.fx, camera.fy, pixels. */
    public static final Range FOCAL_PX = new Range(1, 1e6);
    /** camera.cx, camera.cy, pixels of the full frame; also within [-size, 2 size] of the full frame. */
    public static final Range PRINCIPAL_PX = new Range(-100_000, 200_000);
    /** Each OpenCV distortion coefficient. */
    public static final Range DISTORTION = new Range(-1000, 1000);
    /** camera.pixel_size_m. */
    public static final Range PIXEL_SIZE_M = new Range(1e-9, 1e-2);
    /** camera.focal_length_m. */
    public static final Range FOCAL_LENGTH_M = new Range(1e-4, 1);
    /** exposure_s: Camera2 counts exposure in whole nanoseconds. */
    public static final Range EXPOSURE_S = new Range(1e-9, 3600);
    public static final Range ISO = new Range(1, 1e7);
    public static final Range ROLLING_SHUTTER_SKEW_S = new Range(0, 1);
    /**
     * heading_deg, compass_bearing_deg, a beacon's yaw_deg and a map's bearing_deg: one turn either way.
     */
    public static final Range ANGLE_DEG = new Range(-360, 360);
    /** Each component of gravity_camera (a unit vector or m/s^2). */
    public static final Range GRAVITY = new Range(-100, 100);
    /** gravity_camera must have a direction: its length at least this. */
    public static final double MIN_GRAVITY_NORM = 1e-6;
    /** Each component of angular_velocity_camera_dps, deg/s: phone gyroscopes read up to 2000. */
    public static final Range ANGULAR_RATE_DPS = new Range(-4000, 4000);
    /** timestamp_ns is within [0, 2^63): any non-negative Java long. */
    public static final long MIN_TIMESTAMP_NS = 0;
    /** Each coordinate of a beacon's center_m, metres (room for projected coordinates). */
    public static final Range COORDINATE_M = new Range(-1e7, 1e7);
    /** A beacon's side_m, width_m, height_m and diameter_m (whichever its shape gives). */
    public static final Range BEACON_SIZE_M = new Range(0.005, 10);
    /** A beacon's corner_radius_m (also below half its shorter side; a circle has none). */
    public static final Range CORNER_RADIUS_M = new Range(0, 5);

    /** The service's names of maps and ids of profiles (shared_schemas/api.py, NAME_PATTERN). */
    public static final Pattern NAME = Pattern.compile("[A-Za-z0-9][A-Za-z0-9_.-]{0,63}");

    /** @throws ContractException naming {@code field} when {@code name} is not one of {@link #NAME} */
    public static String checkName(String field, String name) {
        if (name == null || !NAME.matcher(name).matches()) {
            throw new ContractException(field, "must match " + NAME.pattern() + ", got '" + name + "'");
        }
        return name;
    }

    /** @throws ContractException when {@code v} is negative (a Long is always below 2^63) */
    public static Long checkTimestampNs(String field, Long v) {
        if (v != null && v < MIN_TIMESTAMP_NS) {
            throw new ContractException(field, "must be >= 0, got " + v);
        }
        return v;
    }

    /** A principal point coordinate within [-size, 2 size] of the full frame's width or height. */
    public static double checkPrincipalPoint(String field, double v, int fullSize) {
        PRINCIPAL_PX.check(field, v);
        if (!(v >= -fullSize && v <= 2.0 * fullSize)) {
            throw new ContractException(field, "must be within [-" + fullSize + ", " + 2L * fullSize
                    + "] (the full frame's size beyond either edge), got " + v);
        }
        return v;
    }

    /** Each component within {@link #GRAVITY} and the length at least {@link #MIN_GRAVITY_NORM}. */
    public static double[] checkGravity(String field, double[] g) {
        if (g == null) {
            return null;
        }
        GRAVITY.checkEach(field, g);
        double norm = 0;
        for (double v : g) {
            norm += v * v;
        }
        if (!(Math.sqrt(norm) >= MIN_GRAVITY_NORM)) {
            throw new ContractException(field, "must not be the zero vector (length " + Math.sqrt(norm) + ")");
        }
        return g;
    }
}
