package io.lumipose.client.sensor;

import static org.junit.jupiter.api.Assertions.assertArrayEquals;
import static org.junit.jupiter.api.Assertions.assertThrows;

import org.junit.jupiter.api.Test;

/**
 * The gyroscope's rate turned into the camera frame by the mount gravity uses, for the devices the
 * gravity tests use: the back camera at 90 deg and the front camera at 270 deg.
 */
class GyroTransformTest {
    /** 1 rad/s in deg/s. */
    private static final double DPS = Math.toDegrees(1);

    /** A rate about the screen's normal (the phone spun flat on a table) is about the optical axis. */
    @Test
    void aRateAboutTheDevicesZAxisIsAboutTheCamerasZAxis() {
        float[] spin = {0, 0, 1};
        // The back lens looks along -z of the device: the same turn reads clockwise along its axis.
        assertArrayEquals(new double[] {0, 0, -DPS}, GyroTransform.deviceToCameraDps(spin, 90, LensFacing.BACK), 1e-9);
        // The front lens looks along +z.
        assertArrayEquals(new double[] {0, 0, DPS},
                GyroTransform.deviceToCameraDps(spin, 270, LensFacing.FRONT), 1e-9);
    }

    /** The landscape sensors lie across the phone: its long (y) axis is the image's x axis. */
    @Test
    void ratesAboutTheDevicesXAndYAxes() {
        // Back at 90: camera x = device -y, camera y = device -x.
        assertArrayEquals(new double[] {-DPS, 0, 0},
                GyroTransform.deviceToCameraDps(new float[] {0, 1, 0}, 90, LensFacing.BACK), 1e-9);
        assertArrayEquals(new double[] {0, -DPS, 0},
                GyroTransform.deviceToCameraDps(new float[] {1, 0, 0}, 90, LensFacing.BACK), 1e-9);
        // Front at 270: camera x = device +y, camera y = device -x.
        assertArrayEquals(new double[] {DPS, 0, 0},
                GyroTransform.deviceToCameraDps(new float[] {0, 1, 0}, 270, LensFacing.FRONT), 1e-9);
        assertArrayEquals(new double[] {0, -DPS, 0},
                GyroTransform.deviceToCameraDps(new float[] {1, 0, 0}, 270, LensFacing.FRONT), 1e-9);
    }

    /**
     * Gravity, fixed in the room, turns in the phone's frame as dg/dt = -omega x g: seen through the
     * camera the same must hold with the camera's rate, for every mount, or the rate was turned
     * otherwise than gravity (a mirror would flip the sign of the cross product).
     */
    @Test
    void gravityTurnsInTheCameraFrameByTheCamerasRate() {
        double[] g = {1.5, 6.0, 7.5};
        double[] omega = {0.3, -0.7, 0.4}; // rad/s
        double dt = 1e-3;
        double[] cross = cross(omega, g);
        float[] gDevice = floats(g);
        float[] gLater = floats(new double[] {g[0] - dt * cross[0], g[1] - dt * cross[1], g[2] - dt * cross[2]});
        for (LensFacing facing : new LensFacing[] {LensFacing.BACK, LensFacing.FRONT}) {
            for (int orientation : new int[] {0, 90, 180, 270}) {
                double norm = Math.sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
                double[] before = scaled(GravityTransform.deviceToCamera(gDevice, orientation, facing), -norm);
                double[] after = scaled(GravityTransform.deviceToCamera(gLater, orientation, facing), -norm);
                double[] omegaCamera = scaled(GyroTransform.deviceToCameraDps(floats(omega), orientation, facing),
                        1 / DPS);
                double[] expected = cross(omegaCamera, before);
                double[] seen = {(before[0] - after[0]) / dt, (before[1] - after[1]) / dt,
                    (before[2] - after[2]) / dt};
                assertArrayEquals(expected, seen, 0.02, facing + " at " + orientation);
            }
        }
    }

    @Test
    void cameraDpsToDeviceUndoesDeviceToCameraDps() {
        double[] rate = {12.5, -3.0, 40.0};
        for (LensFacing facing : new LensFacing[] {LensFacing.BACK, LensFacing.FRONT}) {
            for (int orientation : new int[] {0, 90, 180, 270}) {
                float[] device = GyroTransform.cameraDpsToDevice(rate, orientation, facing);
                assertArrayEquals(rate, GyroTransform.deviceToCameraDps(device, orientation, facing), 1e-4,
                        facing + " at " + orientation);
            }
        }
    }

    @Test
    void badInputIsRejected() {
        assertThrows(IllegalArgumentException.class,
                () -> GyroTransform.deviceToCameraDps(new float[] {0, 0}, 90, LensFacing.BACK));
        assertThrows(IllegalArgumentException.class,
                () -> GyroTransform.deviceToCameraDps(new float[] {0, 0, 1}, 45, LensFacing.BACK));
        assertThrows(IllegalArgumentException.class,
                () -> GyroTransform.cameraDpsToDevice(null, 270, LensFacing.FRONT));
    }

    private static double[] cross(double[] a, double[] b) {
        return new double[] {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
    }

    private static double[] scaled(double[] v, double s) {
        return new double[] {v[0] * s, v[1] * s, v[2] * s};
    }

    private static float[] floats(double[] v) {
        return new float[] {(float) v[0], (float) v[1], (float) v[2]};
    }
}
