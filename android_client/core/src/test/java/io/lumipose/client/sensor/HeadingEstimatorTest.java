package io.lumipose.client.sensor;

import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertNull;
import static org.junit.jupiter.api.Assertions.assertThrows;

import org.junit.jupiter.api.Test;

class HeadingEstimatorTest {
    /** Device-to-ENU for a phone lying screen-up with its top pointing at compass bearing b. */
    private static float[] flatScreenUp(double bearingDeg) {
        double b = Math.toRadians(bearingDeg);
        // Device y (top) -> (sin b, cos b, 0) in ENU; device x (right) -> (cos b, -sin b, 0); z -> up.
        return new float[] {
            (float) Math.cos(b), (float) Math.sin(b), 0,
            (float) -Math.sin(b), (float) Math.cos(b), 0,
            0, 0, 1,
        };
    }

    @Test
    void frontCameraLookingUpWithThePhonesTopNorth() {
        // Front sensor at 270 deg: the image's x axis is the device's +y, here north.
        assertEquals(0.0, HeadingEstimator.cameraYawDeg(flatScreenUp(0), 270, LensFacing.FRONT, 0), 1e-6);
        // Map +X pointing east: north is map +Y, a yaw of +90.
        assertEquals(90.0, HeadingEstimator.cameraYawDeg(flatScreenUp(0), 270, LensFacing.FRONT, 90), 1e-6);
    }

    @Test
    void turningThePhoneClockwiseTurnsTheYawCounterClockwiseNegative() {
        // Seen from above a clockwise turn of 30 deg is a yaw of -30 about +Z.
        assertEquals(-30.0, HeadingEstimator.cameraYawDeg(flatScreenUp(30), 270, LensFacing.FRONT, 0), 1e-5);
        assertEquals(180.0, HeadingEstimator.cameraYawDeg(flatScreenUp(180), 270, LensFacing.FRONT, 0), 1e-5);
        assertEquals(-170.0, HeadingEstimator.cameraYawDeg(flatScreenUp(170), 270, LensFacing.FRONT, 0), 1e-5);
    }

    @Test
    void backCameraLookingUpFromAPhoneLyingScreenDown() {
        // Screen down, top north: device x -> west, y -> north, z -> down.
        float[] screenDown = {-1, 0, 0, 0, 1, 0, 0, 0, -1};
        // Back sensor at 90 deg: the image's x axis is the device's -y, here south.
        assertEquals(180.0, HeadingEstimator.cameraYawDeg(screenDown, 90, LensFacing.BACK, 0), 1e-6);
    }

    @Test
    void noYawWhenTheImageXAxisIsVertical() {
        // Phone upright in portrait (top up, screen facing south): front sensor's x axis = device y = up.
        float[] upright = {1, 0, 0, 0, 0, 1, 0, -1, 0};
        assertNull(HeadingEstimator.cameraYawDeg(upright, 270, LensFacing.FRONT, 0));
        assertThrows(IllegalArgumentException.class,
                () -> HeadingEstimator.cameraYawDeg(new float[4], 270, LensFacing.FRONT, 0));
    }

    /** The compass bearing of the image's x axis, and the heading as the map's bearing minus it. */
    @Test
    void compassBearingAndHeadingSplit() {
        assertEquals(30.0, HeadingEstimator.compassBearingDeg(flatScreenUp(30), 270, LensFacing.FRONT), 1e-5);
        assertEquals(-170.0, HeadingEstimator.compassBearingDeg(flatScreenUp(190), 270, LensFacing.FRONT), 1e-5);
        assertEquals(-30.0, HeadingEstimator.headingDeg(0, 30), 1e-12);
        assertEquals(170.0, HeadingEstimator.headingDeg(350, 180), 1e-12, "wrapped into (-180, 180]");
        assertEquals(180.0, HeadingEstimator.headingDeg(90, -90), 1e-12);
        float[] upright = {1, 0, 0, 0, 0, 1, 0, -1, 0};
        assertNull(HeadingEstimator.compassBearingDeg(upright, 270, LensFacing.FRONT));
        for (double b : new double[] {0, 45, 133, 260, 359}) {
            double compass = HeadingEstimator.compassBearingDeg(flatScreenUp(b), 270, LensFacing.FRONT);
            assertEquals(HeadingEstimator.cameraYawDeg(flatScreenUp(b), 270, LensFacing.FRONT, 77),
                    HeadingEstimator.headingDeg(77, compass), 1e-9);
        }
    }
}
