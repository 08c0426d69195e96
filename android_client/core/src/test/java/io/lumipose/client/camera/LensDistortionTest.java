package io.lumipose.client.camera;

import static org.junit.jupiter.api.Assertions.assertArrayEquals;
import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertThrows;

import org.junit.jupiter.api.Test;

class LensDistortionTest {
    @Test
    void camera2OrderBecomesOpenCvOrder() {
        // Camera2 [k1, k2, k3, p1, p2] -> OpenCV (k1, k2, p1, p2, k3).
        double[] cv = LensDistortion.toOpenCv(new float[] {0.1f, -0.2f, 0.3f, 0.004f, -0.005f});
        assertArrayEquals(new double[] {0.1f, -0.2f, 0.004f, -0.005f, 0.3f}, cv, 0);
    }

    @Test
    void absentOrZeroMeansNone() {
        assertEquals(0, LensDistortion.toOpenCv((double[]) null).length);
        assertEquals(0, LensDistortion.toOpenCv(new float[5]).length);
    }

    @Test
    void wrongLengthIsRejected() {
        assertThrows(IllegalArgumentException.class, () -> LensDistortion.toOpenCv(new float[] {1f, 2f, 3f}));
        assertThrows(IllegalArgumentException.class,
                () -> LensDistortion.toOpenCv(new float[] {Float.NaN, 0f, 0f, 0f, 0f}));
    }

    /**
     * LENS_RADIAL_DISTORTION normalises each axis to 1 at the farther edge. With f = 2000 px and the
     * edge 1000 px away on both axes, x_i = 2 x' (x' = OpenCV's x / f): s = 2, so OpenCV's
     * k1 = 4 kappa_1, k2 = 16 kappa_2, k3 = 64 kappa_3, p1 = 2 kappa_4, p2 = 2 kappa_5.
     */
    @Test
    void radialDistortionIsRescaledToFocalLengthUnits() {
        double[] cv = LensDistortion.fromRadialDistortion(new double[] {1, 0.01, 0.002, 0.0003, 0.004, 0.005},
                2000, 2000, 1000, 1000);
        assertArrayEquals(new double[] {0.04, 0.032, 0.008, 0.01, 0.0192}, cv, 1e-12);
        assertEquals(0, LensDistortion.fromRadialDistortion(null, 1, 1, 1, 1).length);
        assertEquals(0, LensDistortion.fromRadialDistortion(new double[6], 1, 1, 1, 1).length);
        assertThrows(IllegalArgumentException.class,
                () -> LensDistortion.fromRadialDistortion(new double[] {1, 0, 0, 0, 0}, 1, 1, 1, 1));
        assertThrows(IllegalArgumentException.class,
                () -> LensDistortion.fromRadialDistortion(new double[] {0.5, 0.1, 0, 0, 0, 0}, 1, 1, 1, 1));
    }
}
