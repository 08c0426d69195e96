package io.lumipose.client.sensor;

/**
 * Gravity from Android's device frame into the contract's camera frame ({@link CameraMount}).
 * TYPE_GRAVITY reads +9.81 on z when the phone lies screen-up: it points up, the contract's
 * {@code gravity_camera} points down.
 */
public final class GravityTransform {
    /** m/s^2, what TYPE_GRAVITY's length is at rest. */
    public static final double STANDARD_GRAVITY = 9.80665;

    private GravityTransform() {
    }

    /**
     * @param gravityDevice        TYPE_GRAVITY values [x, y, z], m/s^2 (pointing up)
     * @param sensorOrientationDeg {@code SENSOR_ORIENTATION}: 0, 90, 180 or 270
     * @param facing               lens facing
     * @return unit vector of gravity (pointing down) in the camera frame
     */
    public static double[] deviceToCamera(float[] gravityDevice, int sensorOrientationDeg, LensFacing facing) {
        if (gravityDevice == null || gravityDevice.length < 3) {
            throw new IllegalArgumentException("gravity needs 3 values [x, y, z]");
        }
        double x = gravityDevice[0];
        double y = gravityDevice[1];
        double z = gravityDevice[2];
        double norm = Math.sqrt(x * x + y * y + z * z);
        if (!(norm > 1e-3) || Double.isInfinite(norm)) {
            throw new IllegalArgumentException("gravity reading has no direction: |g| = " + norm + " m/s^2");
        }
        return CameraMount.deviceToCamera(new double[] {-x / norm, -y / norm, -z / norm}, sensorOrientationDeg, facing);
    }

    /**
     * The inverse of {@link #deviceToCamera}: what TYPE_GRAVITY reads on a phone whose camera sees
     * gravity along {@code gravityCamera} (a simulated phone replaying a rendered frame).
     *
     * @param gravityCamera gravity (pointing down) in the camera frame, any length
     * @return TYPE_GRAVITY [x, y, z], device frame, m/s^2 (pointing up, length {@link #STANDARD_GRAVITY})
     */
    public static float[] cameraToDevice(double[] gravityCamera, int sensorOrientationDeg, LensFacing facing) {
        if (gravityCamera == null || gravityCamera.length != 3) {
            throw new IllegalArgumentException("gravity needs 3 values [x, y, z]");
        }
        double norm = Math.sqrt(gravityCamera[0] * gravityCamera[0] + gravityCamera[1] * gravityCamera[1]
                + gravityCamera[2] * gravityCamera[2]);
        if (!(norm > 1e-9) || Double.isInfinite(norm)) {
            throw new IllegalArgumentException("gravity has no direction: |g| = " + norm);
        }
        double[] down = CameraMount.cameraToDevice(gravityCamera, sensorOrientationDeg, facing);
        float[] device = new float[3];
        for (int i = 0; i < 3; i++) {
            device[i] = (float) (-STANDARD_GRAVITY * down[i] / norm);
        }
        return device;
    }
}
