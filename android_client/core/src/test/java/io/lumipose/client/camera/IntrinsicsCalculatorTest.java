package io.lumipose.client.camera;

import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertFalse;
import static org.junit.jupiter.api.Assertions.assertThrows;
import static org.junit.jupiter.api.Assertions.assertTrue;

import org.junit.jupiter.api.Test;

class IntrinsicsCalculatorTest {
    // The paper's Mi 8 front camera in sensor orientation: 5184 x 3880 px of 0.9 um, f = 3.52 mm.
    private static final PixelSize MI8_ARRAY = new PixelSize(5184, 3880);
    private static final double MI8_W_MM = 5184 * 0.0009;
    private static final double MI8_H_MM = 3880 * 0.0009;

    @Test
    void focalLengthFallbackIsThePapersEquationNine() {
        Intrinsics k = IntrinsicsCalculator.fromFocalLength(3.52, MI8_W_MM, MI8_H_MM, MI8_ARRAY,
                ArrayRect.ofSize(5184, 3880), MI8_ARRAY, new double[0], "mi8");
        assertEquals(3911.11, k.fx, 0.01);
        assertEquals(3911.11, k.fy, 0.01);
        // The contract's centre, not the paper's width / 2.
        assertEquals((5184 - 1) / 2.0, k.cx, 1e-9);
        assertEquals((3880 - 1) / 2.0, k.cy, 1e-9);
        assertEquals(0.9e-6, k.pixelSizeM, 1e-15);
        assertEquals(3.52e-3, k.focalLengthM, 1e-15);
    }

    @Test
    void focalLengthFallbackScalesToTheOutputSize() {
        // The bundled fixture's size (portrait there): quarter scale gives its 977.78 px focal length.
        Intrinsics k = IntrinsicsCalculator.fromFocalLength(3.52, MI8_W_MM, MI8_H_MM, MI8_ARRAY,
                ArrayRect.ofSize(5184, 3880), new PixelSize(1296, 970), new double[0], "mi8");
        assertEquals(977.7777777777778, k.fx, 1e-9);
        assertEquals(647.5, k.cx, 1e-12);
        assertEquals(484.5, k.cy, 1e-12);
        assertEquals(3.6e-6, k.pixelSizeM, 1e-15);
    }

    @Test
    void calibrationAtFullSizeOnlyShiftsHalfAPixel() {
        float[] cal = {3000f, 3001f, 2000.5f, 1500.25f, 0f};
        Intrinsics k = IntrinsicsCalculator.fromLensCalibration(cal, ArrayRect.ofSize(4000, 3000),
                ArrayRect.ofSize(4000, 3000), new PixelSize(4000, 3000), new double[0], null);
        assertEquals(3000.0, k.fx, 1e-9);
        assertEquals(3001.0, k.fy, 1e-9);
        assertEquals(2000.0, k.cx, 1e-9);
        assertEquals(1499.75, k.cy, 1e-9);
    }

    @Test
    void calibrationCentreStaysCentredAfterScaling() {
        // Camera2's centre of a 4000 x 3000 array is (2000, 1500) in edge coordinates.
        float[] cal = {3200f, 3200f, 2000f, 1500f, 0f};
        Intrinsics quarter = IntrinsicsCalculator.fromLensCalibration(cal, ArrayRect.ofSize(4000, 3000),
                ArrayRect.ofSize(4000, 3000), new PixelSize(1000, 750), new double[0], null);
        assertEquals(800.0, quarter.fx, 1e-9);
        assertEquals(499.5, quarter.cx, 1e-9);
        assertEquals(374.5, quarter.cy, 1e-9);
    }

    @Test
    void calibrationIsCroppedToA16By9Output() {
        // 4:3 array to 1920 x 1080: scale 0.48, 180 rows cropped top and bottom.
        float[] cal = {3200f, 3200f, 2100f, 1400f, 0f};
        Intrinsics k = IntrinsicsCalculator.fromLensCalibration(cal, ArrayRect.ofSize(4000, 3000),
                ArrayRect.ofSize(4000, 3000), new PixelSize(1920, 1080), new double[0], null);
        assertEquals(0.48, IntrinsicsCalculator.scale(ArrayRect.ofSize(4000, 3000), new PixelSize(1920, 1080)), 1e-12);
        assertEquals(1536.0, k.fx, 1e-9);
        assertEquals(0.48 * 2100 - 0.5, k.cx, 1e-9);
        assertEquals(0.48 * 1400 - 180 - 0.5, k.cy, 1e-9);
    }

    @Test
    void calibrationIsMovedFromThePreCorrectionArrayToTheActiveArray() {
        float[] cal = {3200f, 3200f, 2016f, 1512f, 0f};
        Intrinsics k = IntrinsicsCalculator.fromLensCalibration(cal, new ArrayRect(0, 0, 4032, 3024),
                new ArrayRect(16, 12, 4000, 3000), new PixelSize(4000, 3000), new double[0], null);
        assertEquals(1999.5, k.cx, 1e-9);
        assertEquals(1499.5, k.cy, 1e-9);
    }

    @Test
    void zeroCalibrationIsNotUsable() {
        assertFalse(IntrinsicsCalculator.isUsable(new float[5]));
        assertFalse(IntrinsicsCalculator.isUsable(null));
        assertFalse(IntrinsicsCalculator.isUsable(new float[] {1f, 1f, 1f, 1f}));
        assertTrue(IntrinsicsCalculator.isUsable(new float[] {1f, 1f, 0f, 0f, 0f}));
        assertThrows(IllegalArgumentException.class, () -> IntrinsicsCalculator.fromLensCalibration(new float[5],
                ArrayRect.ofSize(10, 10), ArrayRect.ofSize(10, 10), new PixelSize(10, 10), null, null));
        assertThrows(IllegalArgumentException.class, () -> IntrinsicsCalculator.fromFocalLength(0, 1, 1,
                MI8_ARRAY, ArrayRect.ofSize(10, 10), new PixelSize(10, 10), null, null));
    }
}
