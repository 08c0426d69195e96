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
}
