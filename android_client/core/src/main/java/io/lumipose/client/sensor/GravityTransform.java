package io.lumipose.client.sensor;

/**
 * Gravity from Android's device frame into the contract's camera frame.
 *
 * <p>Device frame (Android sensors): x right, y up, z out of the screen, phone in its natural
 * orientation. TYPE_GRAVITY reads +9.81 on z when the phone lies screen-up: it points up, the
 * contract's {@code gravity_camera} points down.
 *
 * <p>Camera frame (OpenCV) of the image as Camera2 delivers it. First the upright image (rotated
 * clockwise by {@code SENSOR_ORIENTATION} for display): a back lens sees (x, -y, -z) of the
 * device, a front lens, whose unmirrored image swaps left and right, sees (-x, -y, z). The
 * delivered image is that one turned back: its x axis is the upright (cos t, sin t) direction and
 * its y axis the upright (-sin t, cos t) direction (image coordinates, y down).
 */
public final class GravityTransform {
    private GravityTransform() {
    }

    /**
     * @param gravityDevice      TYPE_GRAVITY values [x, y, z], m/s^2 (pointing up)
     * @param sensorOrientationDeg {@code SENSOR_ORIENTATION}: 0, 90, 180 or 270
     * @param facing             lens facing
     * @return unit vector of gravity (pointing down) in the camera frame
     */
    public static double[] deviceToCamera(float[] gravityDevice, int sensorOrientationDeg, LensFacing facing) {
        if (gravityDevice == null || gravityDevice.length < 3) {
            throw new IllegalArgumentException("gravity needs 3 values [x, y, z]");
        }
        if (sensorOrientationDeg % 90 != 0 || sensorOrientationDeg < 0 || sensorOrientationDeg >= 360) {
            throw new IllegalArgumentException("SENSOR_ORIENTATION must be 0, 90, 180 or 270, got " + sensorOrientationDeg);
        }
        double x = gravityDevice[0];
        double y = gravityDevice[1];
        double z = gravityDevice[2];
        double norm = Math.sqrt(x * x + y * y + z * z);
        if (!(norm > 1e-3) || Double.isInfinite(norm)) {
            throw new IllegalArgumentException("gravity reading has no direction: |g| = " + norm + " m/s^2");
        }
        // Down, not up.
        x = -x / norm;
        y = -y / norm;
        z = -z / norm;
        double ux;
        double uy;
        double uz;
        if (facing == LensFacing.FRONT) {
            ux = -x;
            uy = -y;
            uz = z;
        } else {
            ux = x;
            uy = -y;
            uz = -z;
        }
        double t = Math.toRadians(sensorOrientationDeg);
        // Exact quarter turns: avoid 6e-17 residues in the sent JSON.
        double c = Math.rint(Math.cos(t));
        double s = Math.rint(Math.sin(t));
        return new double[] {c * ux + s * uy, -s * ux + c * uy, uz};
    }
}
