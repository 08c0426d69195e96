package io.lumipose.client.camera;

import static org.junit.jupiter.api.Assertions.assertArrayEquals;
import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertThrows;
import static org.junit.jupiter.api.Assertions.assertTrue;

import java.util.ArrayList;
import java.util.List;

import org.junit.jupiter.api.Test;

/**
 * Intrinsics of the three fixture devices (src/test/resources/devices/), each worked out by hand
 * from the fixture's numbers. Output pixels use OpenCV's convention: a centred principal point is
 * ((w - 1) / 2, (h - 1) / 2).
 */
class DeviceIntrinsicsTest {
    private static final double EPS = 1e-6;

    /**
     * Logical multi-camera: pixel array 4000x3000 over 6.4 x 4.8 mm, pitch 6.4 / 4000 = 0.0016 mm;
     * focal lengths 2.4 / 4.8 / 9.6 mm; no calibration. Output 2000x1500 from the full array:
     * scale 0.5. The frame's LENS_FOCAL_LENGTH says which lens took it:
     * 4.8 mm: fx = 4.8 / 0.0016 * 0.5 = 1500 px; 9.6 mm: 3000 px. The characteristics'
     * first focal length (2.4 mm, the ultra-wide) would give 750 px, half the truth.
     * Principal point: the array's centre, (2000 - 1) / 2 = 999.5, (1500 - 1) / 2 = 749.5.
     */
    @Test
    void logicalMultiCameraTakesTheFocalLengthFromTheResult() {
        CameraFacts facts = Devices.load(Devices.LOGICAL);
        PixelSize out = new PixelSize(2000, 1500);
        FrameResult wide = result(4.8).cropRegion(new ArrayRect(0, 0, 4000, 3000)).distortionCorrectionMode("off")
                .zoomRatio(1.0).rotateAndCrop("none").build();
        Intrinsics k = IntrinsicsCalculator.forFrame(facts, wide, out);
        assertEquals(1500, k.fx, EPS);
        assertEquals(1500, k.fy, EPS);
        assertEquals(999.5, k.cx, EPS);
        assertEquals(749.5, k.cy, EPS);
        assertEquals(0.0048, k.focalLengthM, EPS);
        assertEquals(3.2e-6, k.pixelSizeM, 1e-15); // 0.0016 mm / 0.5
        assertEquals(0, k.distortion().length);

        assertEquals(3000, IntrinsicsCalculator.forFrame(facts, result(9.6).build(), out).fx, EPS);

        IllegalArgumentException unknownLens = assertThrows(IllegalArgumentException.class,
                () -> IntrinsicsCalculator.forFrame(facts, FrameResult.builder(1).build(), out));
        assertTrue(unknownLens.getMessage().contains("LENS_FOCAL_LENGTH"), unknownLens.getMessage());
    }

    /**
     * Pre-correction array [0, 0, 4080, 3060] around the active array [40, 30, 4000, 3000];
     * pitch 5.712 / 4080 = 0.0014 mm, f = 4.2 mm: f / pitch = 3000 px, which the calibration
     * [3000, 3000, 2040, 1530, 0] agrees with. Distortion correction off: the crop region is the
     * pre-correction array's, so the stream is all 4080x3060 of it, scaled by 2040 / 4080 = 0.5:
     * fx = 1500, cx = 0.5 * 2040 - 0.5 = 1019.5, cy = 0.5 * 1530 - 0.5 = 764.5. LENS_DISTORTION
     * [k1, k2, k3, p1, p2] = [0.1, -0.2, 0.05, 0.001, -0.002] goes to OpenCV's (k1, k2, p1, p2, k3).
     */
    @Test
    void preCorrectionArrayLargerThanTheActiveArray() {
        CameraFacts facts = Devices.load(Devices.PRE_CORRECTION);
        PixelSize out = new PixelSize(2040, 1530);
        List<String> warnings = new ArrayList<String>();
        FrameResult off = result(4.2).cropRegion(new ArrayRect(0, 0, 4080, 3060)).distortionCorrectionMode("off").build();
        Intrinsics k = IntrinsicsCalculator.forFrame(facts, off, out, warnings);
        assertEquals(1500, k.fx, EPS);
        assertEquals(1019.5, k.cx, EPS);
        assertEquals(764.5, k.cy, EPS);
        assertArrayEquals(new double[] {0.1, -0.2, 0.001, -0.002, 0.05}, k.distortion(), EPS);
        assertTrue(warnings.isEmpty(), warnings.toString());

        // Correction on (the request was ignored): the crop is in the active array [40, 30, 4000, 3000],
        // scale max(2040 / 4000, 1530 / 3000) = 0.51, fx = 0.51 * 3000 = 1530; the calibration's
        // centre 2040 lies 40 px into the pre-correction array's margin: cx = 0.51 * (2040 - 40) - 0.5
        // = 1019.5, cy = 0.51 * (1530 - 30) - 0.5 = 764.5; the image is undistorted: none sent, said so.
        FrameResult on = result(4.2).cropRegion(new ArrayRect(0, 0, 4000, 3000)).distortionCorrectionMode("fast").build();
        Intrinsics corrected = IntrinsicsCalculator.forFrame(facts, on, out, warnings);
        assertEquals(1530, corrected.fx, EPS);
        assertEquals(1019.5, corrected.cx, EPS);
        assertEquals(764.5, corrected.cy, EPS);
        assertEquals(0, corrected.distortion().length);
        assertEquals(1, warnings.size());
    }

    /**
     * Front camera at 270 deg, sized like the Mi 8's: 5184x3880 pixels over 4.6656 x 3.492 mm,
     * pitch 0.0009 mm, one focal length 3.52 mm (the result need not say it): f / pitch =
     * 3911.11 px; output 1296x970 = a quarter: fx = 977.78 px, principal point (647.5, 484.5).
     * No distortion-correction modes: the stream is the active array.
     */
    @Test
    void frontCameraAtSensorOrientation270() {
        CameraFacts facts = Devices.load(Devices.FRONT_270);
        Intrinsics k = IntrinsicsCalculator.forFrame(facts, FrameResult.builder(1).build(), new PixelSize(1296, 970));
        assertEquals(3.52 / 0.0009 / 4, k.fx, EPS);
        assertEquals(977.777778, k.fx, 1e-6);
        assertEquals(647.5, k.cx, EPS);
        assertEquals(484.5, k.cy, EPS);
    }

    @Test
    void theResultsCalibrationAndDistortionWinOverTheCharacteristics() {
        CameraFacts facts = Devices.load(Devices.PRE_CORRECTION);
        FrameResult r = result(4.2).distortionCorrectionMode("off")
                .lensIntrinsicCalibration(new double[] {3100, 3100, 2000, 1500, 0})
                .lensDistortion(new double[] {0.3, 0, 0, 0, 0}).build();
        Intrinsics k = IntrinsicsCalculator.forFrame(facts, r, new PixelSize(2040, 1530));
        assertEquals(1550, k.fx, EPS); // 0.5 * 3100
        assertEquals(999.5, k.cx, EPS); // 0.5 * 2000 - 0.5
        assertArrayEquals(new double[] {0.3, 0, 0, 0, 0}, k.distortion(), EPS);
    }

    /**
     * LENS_RADIAL_DISTORTION when there is no LENS_DISTORTION: kappa normalised by the distance to
     * the farther edge, 2040 px and 1530 px from the principal point; f = 3000 px on both axes, so
     * s = sqrt(3000 / 2040 * 3000 / 1530) and k1 = kappa_1 s^2, p1 = kappa_4 s.
     */
    @Test
    void radialDistortionIsTheFallback() {
        CameraFacts facts = Devices.load(Devices.PRE_CORRECTION).toBuilder().lensDistortion(null).build();
        FrameResult r = result(4.2).distortionCorrectionMode("off")
                .lensRadialDistortion(new double[] {1, 0.02, 0, 0, 0.001, 0}).build();
        double s = Math.sqrt(3000.0 / 2040 * (3000.0 / 1530));
        Intrinsics k = IntrinsicsCalculator.forFrame(facts, r, new PixelSize(2040, 1530));
        assertArrayEquals(new double[] {0.02 * s * s, 0, 0.001 * s, 0, 0}, k.distortion(), 1e-12);
    }

    @Test
    void aMalformedDistortionIsNoDistortionWithAWarning() {
        CameraFacts facts = Devices.load(Devices.PRE_CORRECTION);
        List<String> warnings = new ArrayList<String>();
        FrameResult threeValues = result(4.2).distortionCorrectionMode("off")
                .lensDistortion(new double[] {0.1, 0.2, 0.3}).build();
        Intrinsics k = IntrinsicsCalculator.forFrame(facts, threeValues, new PixelSize(2040, 1530), warnings);
        assertEquals(0, k.distortion().length);
        assertEquals(1, warnings.size());
        assertTrue(warnings.get(0).contains("LENS_DISTORTION"), warnings.get(0));

        warnings.clear();
        FrameResult badKappa0 = result(4.2).distortionCorrectionMode("off")
                .lensRadialDistortion(new double[] {0, 0.1, 0, 0, 0, 0}).build();
        CameraFacts noModern = facts.toBuilder().lensDistortion(null).build();
        assertEquals(0, IntrinsicsCalculator.forFrame(noModern, badKappa0, new PixelSize(2040, 1530), warnings)
                .distortion().length);
        assertTrue(warnings.get(0).contains("kappa_0"), warnings.get(0));
    }

    @Test
    void aCalibrationFarFromFocalLengthOverPitchIsSetAsideAndAPrincipalPointOutsideIsRefused() {
        CameraFacts facts = Devices.load(Devices.PRE_CORRECTION);
        // 3400 / 3000 = 1.13: more than 10 % off; the focal length's 3000 px (at scale 1/2: 1500) is used instead.
        FrameResult r = result(4.2).lensIntrinsicCalibration(new double[] {3400, 3400, 2040, 1530, 0}).build();
        List<String> warnings = new ArrayList<String>();
        Intrinsics fromFocal = IntrinsicsCalculator.forFrame(facts, r, new PixelSize(2040, 1530), warnings);
        assertEquals(IntrinsicsCalculator.forFrame(facts, result(4.2).build(), new PixelSize(2040, 1530)).fx,
                fromFocal.fx, EPS);
        assertTrue(warnings.toString().contains("not within 10 %"), warnings.toString());
        FrameResult outside = result(4.2).lensIntrinsicCalibration(new double[] {3000, 3000, 5000, 1530, 0}).build();
        IllegalArgumentException e = assertThrows(IllegalArgumentException.class,
                () -> IntrinsicsCalculator.forFrame(facts, outside, new PixelSize(2040, 1530)));
        assertTrue(e.getMessage().contains("principal point"), e.getMessage());
    }

    /** The characteristics' calibration of a logical camera may be another lens': then the focal length rules. */
    @Test
    void aCharacteristicsCalibrationOfAnotherLensIsSetAside() {
        CameraFacts facts = Devices.load(Devices.LOGICAL).toBuilder()
                .lensIntrinsicCalibration(new double[] {1500, 1500, 2000, 1500, 0}).build(); // the 2.4 mm lens
        List<String> warnings = new ArrayList<String>();
        Intrinsics k = IntrinsicsCalculator.forFrame(facts, result(4.8).distortionCorrectionMode("off").build(),
                new PixelSize(2000, 1500), warnings);
        assertEquals(1500, k.fx, EPS); // 4.8 / 0.0016 * 0.5, not 1500 * 0.5
        assertEquals(1, warnings.size());
    }

    @Test
    void zoomRotateAndCropAndACropOutsideTheArrayAreRefused() {
        CameraFacts facts = Devices.load(Devices.LOGICAL);
        PixelSize out = new PixelSize(2000, 1500);
        assertTrue(assertThrows(IllegalArgumentException.class, () -> IntrinsicsCalculator.forFrame(facts,
                result(4.8).zoomRatio(2.0).build(), out)).getMessage().contains("CONTROL_ZOOM_RATIO"));
        assertTrue(assertThrows(IllegalArgumentException.class, () -> IntrinsicsCalculator.forFrame(facts,
                result(4.8).rotateAndCrop("90").build(), out)).getMessage().contains("SCALER_ROTATE_AND_CROP"));
        assertTrue(assertThrows(IllegalArgumentException.class, () -> IntrinsicsCalculator.forFrame(facts,
                result(4.8).cropRegion(new ArrayRect(100, 0, 4000, 3000)).build(), out)).getMessage()
                .contains("SCALER_CROP_REGION"));
    }

    /** A centred half-size crop region doubles the focal length in output pixels. */
    @Test
    void theCropRegionIsTheStreamsSource() {
        CameraFacts facts = Devices.load(Devices.LOGICAL);
        FrameResult r = result(4.8).distortionCorrectionMode("off").cropRegion(new ArrayRect(1000, 750, 2000, 1500)).build();
        Intrinsics k = IntrinsicsCalculator.forFrame(facts, r, new PixelSize(2000, 1500));
        assertEquals(3000, k.fx, EPS); // 3000 px at scale 1
        assertEquals(999.5, k.cx, EPS); // the array's centre 2000 is the crop's 1000
    }

    private static FrameResult.Builder result(double focalLengthMm) {
        return FrameResult.builder(1_000L).focalLengthMm(focalLengthMm);
    }
}
