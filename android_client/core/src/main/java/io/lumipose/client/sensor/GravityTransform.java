package io.lumipose.client.sensor;

/**
 * Gravity from Android's device frame into the contract's camera frame ({@link CameraMount}).
 * TYPE_GRAVITY reads +9.81 on z when the phone lies screen-up: it points up, the contract's
 * {@code gravity_camera} points down.
 */
public final class GravityTransform {
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
        double[][] mount = CameraMount.cameraFromDevice(sensorOrientationDeg, facing);
        double x = gravityDevice[0];
        double y = gravityDevice[1];
        double z = gravityDevice[2];
        double norm = Math.sqrt(x * x + y * y + z * z);
        if (!(norm > 1e-3) || Double.isInfinite(norm)) {
            throw new IllegalArgumentException("gravity reading has no direction: |g| = " + norm + " m/s^2");
        }
        return CameraMount.apply(mount, new double[] {-x / norm, -y / norm, -z / norm});
    }
}
