package io.lumipose.client.sensor;

/**
 * The contract's {@code compass_bearing_deg} (the compass bearing of the image's +x axis laid level)
 * and {@code heading_deg} (the camera's yaw about +Z in the map frame) from the phone's
 * rotation-vector sensor. The server needs the heading only to pick among a square panel's four
 * look-alike orientations, so the compass's indoor error (often 10-20 deg) is harmless below 45 deg;
 * a survey measures the map's own bearing from the frames' compass bearings.
 *
 * <p>The map's orientation on the compass is its {@code bearing_deg} (or a setting): the bearing
 * (deg clockwise from north) of the map's +X axis. The map is right-handed with +Z up, so +Y lies at
 * that bearing minus 90, and heading = map bearing - compass bearing.
 */
public final class HeadingEstimator {
    /** Below this horizontal length the camera's x axis is too steep to give a bearing. */
    private static final double MIN_HORIZONTAL = 0.2;

    private HeadingEstimator() {
    }

    /**
     * @param deviceToEnu          row-major 3x3 from {@code SensorManager.getRotationMatrixFromVector}:
     *                             device coordinates to East-North-Up
     * @param sensorOrientationDeg {@code SENSOR_ORIENTATION}
     * @param facing               lens facing
     * @return the compass bearing of the image's +x axis laid level, deg clockwise from north in
     *         (-180, 180], or null when that axis points nearly straight up or down (the phone on edge)
     */
    public static Double compassBearingDeg(float[] deviceToEnu, int sensorOrientationDeg, LensFacing facing) {
        if (deviceToEnu == null || deviceToEnu.length != 9) {
            throw new IllegalArgumentException("rotation matrix needs 9 values (row-major 3x3)");
        }
        double[] xDevice = CameraMount.cameraFromDevice(sensorOrientationDeg, facing)[0];
        double east = 0;
        double north = 0;
        for (int i = 0; i < 3; i++) {
            east += deviceToEnu[i] * xDevice[i];
            north += deviceToEnu[3 + i] * xDevice[i];
        }
        if (Math.hypot(east, north) < MIN_HORIZONTAL) {
            return null;
        }
        return wrapDeg(Math.toDegrees(Math.atan2(east, north)));
    }

    /**
     * The contract's heading_deg = {@code mapXBearingDeg} - {@code compassBearingDeg}, in (-180, 180]
     * (a compass bearing is clockwise, a yaw about +Z counter-clockwise).
     */
    public static double headingDeg(double mapXBearingDeg, double compassBearingDeg) {
        return wrapDeg(mapXBearingDeg - compassBearingDeg);
    }

    /**
     * {@link #compassBearingDeg} turned into the camera's yaw in the map frame, deg in (-180, 180], or
     * null when the image's x axis points nearly straight up or down.
     *
     * @param mapXBearingDeg compass bearing of the map's +X axis, deg clockwise from north
     */
    public static Double cameraYawDeg(float[] deviceToEnu, int sensorOrientationDeg, LensFacing facing,
                                      double mapXBearingDeg) {
        Double bearing = compassBearingDeg(deviceToEnu, sensorOrientationDeg, facing);
        return bearing == null ? null : headingDeg(mapXBearingDeg, bearing);
    }

    private static double wrapDeg(double deg) {
        double a = deg % 360.0;
        if (a <= -180) {
            a += 360;
        } else if (a > 180) {
            a -= 360;
        }
        return a;
    }
}
