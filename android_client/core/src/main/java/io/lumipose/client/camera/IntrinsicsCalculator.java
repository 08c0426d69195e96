package io.lumipose.client.camera;

import java.util.ArrayList;
import java.util.List;

/**
 * Intrinsics for an output stream, from what Camera2 reports: {@link #forFrame} per frame, from its
 * capture result; the two older building blocks below take the values directly.
 *
 * <p>An output stream is the source rectangle (the crop region) scaled by
 * s = max(w / W, h / H) and centre-cropped to w x h. The mapping is applied in edge coordinates
 * (pixel centres at x + 0.5, Camera2's convention); the contract's OpenCV convention (centres at
 * integers) is then half a pixel less. Shifting before scaling would be wrong by (s - 1) / 2 px.
 */
public final class IntrinsicsCalculator {
    private IntrinsicsCalculator() {
    }

    /**
     * From {@code LENS_INTRINSIC_CALIBRATION} = [fx, fy, cx, cy, s], given in the pre-correction
     * active array with pixel centres at (x + 0.5, y + 0.5).
     *
     * @param calibration  the five Camera2 values
     * @param preCorrection {@code SENSOR_INFO_PRE_CORRECTION_ACTIVE_ARRAY_SIZE} (pixel-array coordinates)
     * @param streamSource the rectangle the stream is scaled from, usually {@code SENSOR_INFO_ACTIVE_ARRAY_SIZE}
     * @param output       the output size
     * @param distortionOpenCv OpenCV-order distortion (see {@link LensDistortion}), may be empty
     */
    public static Intrinsics fromLensCalibration(float[] calibration, ArrayRect preCorrection, ArrayRect streamSource,
                                                 PixelSize output, double[] distortionOpenCv, String device) {
        if (!isUsable(calibration)) {
            throw new IllegalArgumentException("LENS_INTRINSIC_CALIBRATION must be 5 finite values with fx, fy > 0");
        }
        double scale = scale(streamSource, output);
        double[] principal = principalPoint(calibration[2], calibration[3], preCorrection, streamSource, output);
        return new Intrinsics(scale * calibration[0], scale * calibration[1], principal[0], principal[1],
                distortionOpenCv, null, null, device);
    }

    /** fx must lie within this fraction of focal length / pixel pitch. */
    public static final double FOCAL_TOLERANCE = 0.10;

    /** As {@link #forFrame(CameraFacts, FrameResult, PixelSize, List)}, dropping the warnings. */
    public static Intrinsics forFrame(CameraFacts facts, FrameResult result, PixelSize output) {
        return forFrame(facts, result, output, new ArrayList<String>());
    }

    /**
     * The intrinsics of one frame, from what its capture result says: the lens in use (a logical
     * multi-camera switches physical lenses, so LENS_INFO_AVAILABLE_FOCAL_LENGTHS[0] may be another
     * lens), its calibration and distortion when reported, else the characteristics'; the stream's
     * source rectangle is the frame's SCALER_CROP_REGION.
     *
     * @param warnings receives what the user should know (a malformed distortion key is "no
     *                 distortion" with a warning, not a refusal)
     * @throws IllegalArgumentException naming what is wrong when the frame's geometry is not the
     *         one the maths assumes (zoom, rotate-and-crop, crop outside the array) or fx or the
     *         principal point fail the sanity checks
     */
    public static Intrinsics forFrame(CameraFacts facts, FrameResult result, PixelSize output, List<String> warnings) {
        if (result.zoomRatio != null && Math.abs(result.zoomRatio - 1) > 1e-3) {
            throw new IllegalArgumentException("CONTROL_ZOOM_RATIO is " + result.zoomRatio + ", the intrinsics assume 1");
        }
        if (result.rotateAndCrop != null && !"none".equals(result.rotateAndCrop)) {
            throw new IllegalArgumentException("SCALER_ROTATE_AND_CROP is " + result.rotateAndCrop
                    + ": the stream is rotated or cropped, the intrinsics assume none");
        }
        boolean corrected = isCorrected(facts, result, warnings);
        ArrayRect pre = facts.preCorrectionOrActive();
        ArrayRect source = streamSource(facts, result.cropRegion, corrected);

        double focalMm = focalLengthMm(facts, result);
        double fxFromFocal = focalMm / facts.pixelPitchXMm();
        double fyFromFocal = focalMm / facts.pixelPitchYMm();

        // [fx, fy, cx, cy] in the pre-correction array, pixel centres at x + 0.5.
        double[] k = calibration(facts, result, fxFromFocal, warnings);
        boolean calibrated = k != null;
        if (!calibrated) {
            k = new double[] {fxFromFocal, fyFromFocal, pre.width / 2.0, pre.height / 2.0};
        }
        if (k[2] < 0 || k[2] > pre.width || k[3] < 0 || k[3] > pre.height) {
            throw new IllegalArgumentException("principal point (" + k[2] + ", " + k[3]
                    + ") lies outside the pre-correction array " + pre.width + "x" + pre.height);
        }
        double[] distortion = corrected ? new double[0] : distortion(facts, result, k, pre, calibrated, warnings);
        double scale = scale(source, output);
        double[] principal = principalPoint(k[2], k[3], pre, source, output);
        Double pixelSizeM = calibrated ? null : facts.pixelPitchXMm() * 1e-3 / scale;
        Double focalLengthM = calibrated ? null : focalMm * 1e-3;
        return new Intrinsics(scale * k[0], scale * k[1], principal[0], principal[1], distortion,
                pixelSizeM, focalLengthM, null);
    }

    /**
     * The rectangle of the pixel array the stream is scaled from: the crop region, whose
     * coordinates are the pre-correction array's when distortion correction is off on a device
     * that has it, else the active array's. Null crop = the whole of that array.
     */
    public static ArrayRect streamSource(CameraFacts facts, ArrayRect cropRegion, boolean corrected) {
        ArrayRect base = !corrected && !facts.distortionCorrectionModes.isEmpty()
                ? facts.preCorrectionOrActive() : facts.activeArray;
        if (cropRegion == null) {
            return base;
        }
        if (cropRegion.left < 0 || cropRegion.top < 0 || cropRegion.left + cropRegion.width > base.width
                || cropRegion.top + cropRegion.height > base.height) {
            throw new IllegalArgumentException("SCALER_CROP_REGION " + cropRegion + " exceeds its array "
                    + base.width + "x" + base.height);
        }
        return new ArrayRect(base.left + cropRegion.left, base.top + cropRegion.top, cropRegion.width, cropRegion.height);
    }

    /** The image was geometrically corrected by the device: its coordinates are the active array's, undistorted. */
    private static boolean isCorrected(CameraFacts facts, FrameResult result, List<String> warnings) {
        String mode = result.distortionCorrectionMode;
        if (mode == null) {
            if (!facts.distortionCorrectionModes.isEmpty()) {
                warnings.add("DISTORTION_CORRECTION_MODE not in the result: assumed off, as asked");
            }
            return false;
        }
        if ("off".equals(mode)) {
            return false;
        }
        warnings.add("distortion correction " + mode + " was applied: the image is undistorted, no distortion sent");
        return true;
    }

    private static double focalLengthMm(CameraFacts facts, FrameResult result) {
        if (result.focalLengthMm != null) {
            if (!(result.focalLengthMm > 0)) {
                throw new IllegalArgumentException("LENS_FOCAL_LENGTH must be > 0 mm, got " + result.focalLengthMm);
            }
            return result.focalLengthMm;
        }
        double[] available = facts.availableFocalLengthsMm();
        if (available.length != 1) {
            throw new IllegalArgumentException("the result has no LENS_FOCAL_LENGTH and the camera lists "
                    + available.length + " focal lengths: which lens took the frame is unknown");
        }
        return available[0];
    }

    /**
     * [fx, fy, cx, cy] from the result's LENS_INTRINSIC_CALIBRATION, else the characteristics' when
     * it agrees with the frame's focal length (on a logical multi-camera it may be another lens');
     * null when neither is usable.
     */
    private static double[] calibration(CameraFacts facts, FrameResult result, double fxFromFocal,
                                        List<String> warnings) {
        double[] fromResult = result.lensIntrinsicCalibration();
        if (isUsable(fromResult)) {
            if (agrees(fromResult[0], fxFromFocal)) {
                return fromResult;
            }
            // some HALs report it for another resolution or lens: one bad key must not blind the camera
            warnings.add(String.format(java.util.Locale.ROOT, "the result's LENS_INTRINSIC_CALIBRATION fx %.1f px "
                    + "is not within 10 %% of focal length / pixel pitch %.1f px: intrinsics from the focal length",
                    fromResult[0], fxFromFocal));
            return null;
        }
        double[] fromFacts = facts.lensIntrinsicCalibration();
        if (!isUsable(fromFacts)) {
            return null;
        }
        if (!agrees(fromFacts[0], fxFromFocal)) {
            warnings.add(String.format(java.util.Locale.ROOT, "the characteristics' LENS_INTRINSIC_CALIBRATION "
                    + "(fx %.1f px) is not the frame's lens (%.1f px): intrinsics from the focal length",
                    fromFacts[0], fxFromFocal));
            return null;
        }
        return fromFacts;
    }

    private static boolean agrees(double fx, double fxFromFocal) {
        return Math.abs(fx / fxFromFocal - 1) <= FOCAL_TOLERANCE;
    }

    /**
     * LENS_DISTORTION, else LENS_RADIAL_DISTORTION, from the result, else the characteristics'
     * (those only when they describe this lens: not a logical multi-camera, or its calibration
     * was accepted). A malformed array is "no distortion" with a warning.
     */
    private static double[] distortion(CameraFacts facts, FrameResult result, double[] k, ArrayRect pre,
                                       boolean calibrated, List<String> warnings) {
        boolean factsDescribeThisLens = !facts.isLogicalMultiCamera() || calibrated;
        double[] modern = result.lensDistortion();
        double[] radial = result.lensRadialDistortion();
        if (modern == null && radial == null && factsDescribeThisLens) {
            modern = facts.lensDistortion();
            radial = facts.lensRadialDistortion();
        }
        try {
            if (modern != null) {
                return LensDistortion.toOpenCv(modern);
            }
            double halfWidth = Math.max(k[2], pre.width - k[2]);
            double halfHeight = Math.max(k[3], pre.height - k[3]);
            return LensDistortion.fromRadialDistortion(radial, k[0], k[1], halfWidth, halfHeight);
        } catch (IllegalArgumentException e) {
            warnings.add(e.getMessage() + ": no distortion sent");
            return new double[0];
        }
    }

    private static boolean isUsable(double[] calibration) {
        if (calibration == null || calibration.length != 5) {
            return false;
        }
        for (double v : calibration) {
            if (Double.isNaN(v) || Double.isInfinite(v)) {
                return false;
            }
        }
        return calibration[0] > 0 && calibration[1] > 0;
    }

    /**
     * A principal point given in the pre-correction array (pixel centres at x + 0.5) in the output's
     * OpenCV pixels: shifted to the source rectangle, scaled, centre-cropped, then half a pixel less.
     */
    private static double[] principalPoint(double cxPre, double cyPre, ArrayRect pre, ArrayRect source,
                                           PixelSize output) {
        double scale = scale(source, output);
        double cropX = (scale * source.width - output.width) / 2.0;
        double cropY = (scale * source.height - output.height) / 2.0;
        double cx = scale * (cxPre - (source.left - pre.left)) - cropX - 0.5;
        double cy = scale * (cyPre - (source.top - pre.top)) - cropY - 0.5;
        return new double[] {cx, cy};
    }

    /** Some devices report the key filled with zeros: that means "not calibrated". */
    public static boolean isUsable(float[] calibration) {
        if (calibration == null || calibration.length != 5) {
            return false;
        }
        for (float v : calibration) {
            if (Float.isNaN(v) || Float.isInfinite(v)) {
                return false;
            }
        }
        return calibration[0] > 0 && calibration[1] > 0;
    }

    /**
     * The paper's equation 9: f_px = focal length / pixel pitch, principal point at the centre.
     *
     * @param focalLengthMm    {@code LENS_INFO_AVAILABLE_FOCAL_LENGTHS[0]}, mm
     * @param physicalWidthMm  {@code SENSOR_INFO_PHYSICAL_SIZE} width, mm (covers the pixel array)
     * @param physicalHeightMm {@code SENSOR_INFO_PHYSICAL_SIZE} height, mm
     * @param pixelArray       {@code SENSOR_INFO_PIXEL_ARRAY_SIZE}
     * @param streamSource     the rectangle the stream is scaled from (active array)
     * @param output           the output size
     */
    public static Intrinsics fromFocalLength(double focalLengthMm, double physicalWidthMm, double physicalHeightMm,
                                             PixelSize pixelArray, ArrayRect streamSource, PixelSize output,
                                             double[] distortionOpenCv, String device) {
        if (!(focalLengthMm > 0) || !(physicalWidthMm > 0) || !(physicalHeightMm > 0)) {
            throw new IllegalArgumentException("focal length and physical sensor size must be > 0 mm, got "
                    + focalLengthMm + ", " + physicalWidthMm + " x " + physicalHeightMm);
        }
        double pitchXMm = physicalWidthMm / pixelArray.width;
        double pitchYMm = physicalHeightMm / pixelArray.height;
        double scale = scale(streamSource, output);
        double fx = focalLengthMm / pitchXMm * scale;
        double fy = focalLengthMm / pitchYMm * scale;
        return new Intrinsics(fx, fy, (output.width - 1) / 2.0, (output.height - 1) / 2.0, distortionOpenCv,
                pitchXMm * 1e-3 / scale, focalLengthMm * 1e-3, device);
    }

    /** Scale from the source rectangle to the output: the output is covered, the excess cropped. */
    public static double scale(ArrayRect streamSource, PixelSize output) {
        return Math.max((double) output.width / streamSource.width, (double) output.height / streamSource.height);
    }
}
