package io.lumipose.client.camera;

/**
 * Intrinsics for an output stream, from what Camera2 advertises.
 *
 * <p>An output stream is the source rectangle (the active array) scaled by
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
        double cropX = (scale * streamSource.width - output.width) / 2.0;
        double cropY = (scale * streamSource.height - output.height) / 2.0;
        // Calibration is relative to the pre-correction array; the stream to its source rectangle.
        double cxSource = calibration[2] - (streamSource.left - preCorrection.left);
        double cySource = calibration[3] - (streamSource.top - preCorrection.top);
        double cx = scale * cxSource - cropX - 0.5;
        double cy = scale * cySource - cropY - 0.5;
        return new Intrinsics(scale * calibration[0], scale * calibration[1], cx, cy, distortionOpenCv,
                null, null, device);
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
