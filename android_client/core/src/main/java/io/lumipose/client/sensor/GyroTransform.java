package io.lumipose.client.sensor;

/**
 * The gyroscope's rate from Android's device frame into the contract's camera frame
 * ({@code angular_velocity_camera_dps}), by the same turn as gravity ({@link CameraMount}). The
 * mount is a proper rotation for both lenses (the front lens's left-right swap is part of a half
 * turn, not a mirror), so a rotation rate turns like any vector.
 */
public final class GyroTransform {
    private GyroTransform() {
    }

    /**
     * @param rateDevice TYPE_GYROSCOPE [x, y, z], device frame, rad/s (counter-clockwise positive)
     * @return the rate about the camera's x, y, z axes, deg/s
     */
    public static double[] deviceToCameraDps(float[] rateDevice, int sensorOrientationDeg, LensFacing facing) {
        if (rateDevice == null || rateDevice.length < 3) {
            throw new IllegalArgumentException("rotation rate needs 3 values [x, y, z]");
        }
        double[] camera = CameraMount.deviceToCamera(
                new double[] {rateDevice[0], rateDevice[1], rateDevice[2]}, sensorOrientationDeg, facing);
        for (int i = 0; i < 3; i++) {
            camera[i] = Math.toDegrees(camera[i]);
        }
        return camera;
    }

    /**
     * The inverse of {@link #deviceToCameraDps}: what TYPE_GYROSCOPE reads on a phone whose camera
     * turns at {@code rateCameraDps} (a simulated phone replaying a recorded frame).
     */
    public static float[] cameraDpsToDevice(double[] rateCameraDps, int sensorOrientationDeg, LensFacing facing) {
        if (rateCameraDps == null || rateCameraDps.length != 3) {
            throw new IllegalArgumentException("rotation rate needs 3 values [x, y, z]");
        }
        double[] device = CameraMount.cameraToDevice(rateCameraDps, sensorOrientationDeg, facing);
        return new float[] {(float) Math.toRadians(device[0]), (float) Math.toRadians(device[1]),
            (float) Math.toRadians(device[2])};
    }
}
