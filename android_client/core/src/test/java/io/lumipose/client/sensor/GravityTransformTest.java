package io.lumipose.client.sensor;

import static org.junit.jupiter.api.Assertions.assertArrayEquals;
import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertThrows;

import org.junit.jupiter.api.Test;

class GravityTransformTest {
    private static final float G = 9.81f;

    @Test
    void frontCameraOfAPhoneLyingScreenUpLooksStraightUp() {
        // TYPE_GRAVITY reads +g on z when the screen faces up; the front lens then looks at the ceiling.
        for (int orientation : new int[] {0, 90, 180, 270}) {
            assertArrayEquals(new double[] {0, 0, -1},
                    GravityTransform.deviceToCamera(new float[] {0, 0, G}, orientation, LensFacing.FRONT), 1e-12);
        }
    }

    @Test
    void backCameraOfAPhoneLyingScreenDownLooksStraightUp() {
        assertArrayEquals(new double[] {0, 0, -1},
                GravityTransform.deviceToCamera(new float[] {0, 0, -G}, 90, LensFacing.BACK), 1e-12);
    }

    @Test
    void uprightPortraitPhonePutsGravityAcrossTheLandscapeSensor() {
        float[] upright = {0, G, 0};
        // Back sensor at 90 deg: its image is turned a quarter counter-clockwise, so "down" is +x.
        assertArrayEquals(new double[] {1, 0, 0}, GravityTransform.deviceToCamera(upright, 90, LensFacing.BACK), 1e-12);
        // Front sensor at 270 deg: turned a quarter clockwise, "down" is -x.
        assertArrayEquals(new double[] {-1, 0, 0},
                GravityTransform.deviceToCamera(upright, 270, LensFacing.FRONT), 1e-12);
        // A sensor already upright: down is +y of the image.
        assertArrayEquals(new double[] {0, 1, 0}, GravityTransform.deviceToCamera(upright, 0, LensFacing.BACK), 1e-12);
        assertArrayEquals(new double[] {0, -1, 0}, GravityTransform.deviceToCamera(upright, 180, LensFacing.BACK), 1e-12);
    }

    @Test
    void phoneHeldInLandscapeWithItsRightSideDown() {
        // The device's +x points down, so gravity reads -g on x.
        float[] rightDown = {-G, 0, 0};
        // Back camera at orientation 0: image right is device right, so down is +x in the image.
        assertArrayEquals(new double[] {1, 0, 0}, GravityTransform.deviceToCamera(rightDown, 0, LensFacing.BACK), 1e-12);
        // Front camera at orientation 0 mirrors left and right.
        assertArrayEquals(new double[] {-1, 0, 0},
                GravityTransform.deviceToCamera(rightDown, 0, LensFacing.FRONT), 1e-12);
    }

    @Test
    void tiltIsKeptAndTheResultIsAUnitVector() {
        // Phone lying screen-up, its top end raised 5 deg: gravity gains +y in the device frame.
        double tilt = Math.toRadians(5);
        float[] g = {0, (float) (G * Math.sin(tilt)), (float) (G * Math.cos(tilt))};
        double[] cam = GravityTransform.deviceToCamera(g, 0, LensFacing.FRONT);
        assertEquals(1.0, Math.sqrt(cam[0] * cam[0] + cam[1] * cam[1] + cam[2] * cam[2]), 1e-6);
        // Down in the device is -y (towards the bottom edge); the front lens's image y is -y_device: +y.
        assertEquals(Math.sin(tilt), cam[1], 1e-6);
        assertEquals(-Math.cos(tilt), cam[2], 1e-6);
    }

    @Test
    void badInputIsRejected() {
        assertThrows(IllegalArgumentException.class,
                () -> GravityTransform.deviceToCamera(new float[] {0, 0, G}, 45, LensFacing.BACK));
        assertThrows(IllegalArgumentException.class,
                () -> GravityTransform.deviceToCamera(new float[] {0, 0, 0}, 90, LensFacing.BACK));
        assertThrows(IllegalArgumentException.class,
                () -> GravityTransform.deviceToCamera(new float[] {0, 0}, 90, LensFacing.BACK));
    }

    @Test
    void cameraToDeviceUndoesDeviceToCameraForEveryMount() {
        double[][] directions = {{0, 0, -1}, {0.3, -0.2, -0.93}, {1, 0, 0}, {-0.1, 0.99, 0.05}};
        for (LensFacing facing : LensFacing.values()) {
            for (int orientation : new int[] {0, 90, 180, 270}) {
                for (double[] d : directions) {
                    double norm = Math.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
                    float[] device = GravityTransform.cameraToDevice(d, orientation, facing);
                    assertEquals(GravityTransform.STANDARD_GRAVITY,
                            Math.sqrt(device[0] * device[0] + device[1] * device[1] + device[2] * device[2]), 1e-5);
                    double[] back = GravityTransform.deviceToCamera(device, orientation, facing);
                    assertArrayEquals(new double[] {d[0] / norm, d[1] / norm, d[2] / norm}, back, 1e-6,
                            facing + " at " + orientation + " deg");
                }
            }
        }
    }

    @Test
    void frontCameraLookingStraightUpMeansScreenUp() {
        // The front lens sees gravity along its -z when it faces the ceiling: the phone lies screen-up.
        assertArrayEquals(new float[] {0, 0, (float) GravityTransform.STANDARD_GRAVITY},
                GravityTransform.cameraToDevice(new double[] {0, 0, -1}, 270, LensFacing.FRONT), 1e-6f);
        assertThrows(IllegalArgumentException.class,
                () -> GravityTransform.cameraToDevice(new double[] {0, 0, 0}, 270, LensFacing.FRONT));
    }
}
