package io.lumipose.client.sensor;

/**
 * The contract's {@code heading_deg} (the camera's yaw about +Z in the map frame) from the phone's
 * rotation-vector sensor. The server needs it only to pick among a square panel's four look-alike
 * orientations, so the compass's indoor error (often 10-20 deg) is harmless below 45 deg.
 *
 * <p>The map's orientation on the compass is a setting: the bearing (deg clockwise from north) of
 * the map's +X axis. The map is right-handed with +Z up, so +Y lies at that bearing minus 90.
 */
public final class HeadingEstimator {
    /** Below this horizontal length the camera's x axis is too steep to give a yaw. */
    private static final double MIN_HORIZONTAL = 0.2;

    private HeadingEstimator() {
    }

    /**
     * @param deviceToEnu          row-major 3x3 from {@code SensorManager.getRotationMatrixFromVector}:
     *                             device coordinates to East-North-Up
     * @param sensorOrientationDeg {@code SENSOR_ORIENTATION}
     * @param facing               lens facing
     * @param mapXBearingDeg       compass bearing of the map's +X axis, deg clockwise from north
     * @return the camera's yaw in the map frame, deg in (-180, 180], or null when the image's x axis
     *         points nearly straight up or down (the phone held on edge)
     */
    public static Double cameraYawDeg(float[] deviceToEnu, int sensorOrientationDeg, LensFacing facing,
                                      double mapXBearingDeg) {
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
        double bearing = Math.toDegrees(Math.atan2(east, north));
        double yaw = mapXBearingDeg - bearing;
        yaw = yaw % 360.0;
        if (yaw <= -180) {
            yaw += 360;
        } else if (yaw > 180) {
            yaw -= 360;
        }
        return yaw;
    }
}
