package io.lumipose.client.camera;

/** Camera2's distortion keys turned into OpenCV's coefficients (k1, k2, p1, p2, k3). */
public final class LensDistortion {
    private LensDistortion() {
    }

    /**
     * Camera2 (API 28) gives [k1, k2, k3, p1, p2] (three radial, then two tangential) in the same
     * focal-length-normalised coordinates as OpenCV; OpenCV wants (k1, k2, p1, p2, k3).
     *
     * @param camera2 the five Camera2 coefficients, or null when the key is absent
     * @return OpenCV's five coefficients; empty when absent or all zero (no distortion)
     */
    public static double[] toOpenCv(float[] camera2) {
        return toOpenCv(toDoubles(camera2));
    }

    public static double[] toOpenCv(double[] camera2) {
        if (camera2 == null) {
            return new double[0];
        }
        if (camera2.length != 5) {
            throw new IllegalArgumentException("LENS_DISTORTION must hold 5 values [k1, k2, k3, p1, p2], got "
                    + camera2.length);
        }
        if (isZero(camera2, "LENS_DISTORTION")) {
            return new double[0];
        }
        return new double[] {camera2[0], camera2[1], camera2[3], camera2[4], camera2[2]};
    }

    /**
     * The deprecated {@code LENS_RADIAL_DISTORTION} (API 23-27): [kappa_0 .. kappa_5], where kappa_0
     * is the constant radial term (1 for a sane lens), kappa_1..3 the r^2, r^4, r^6 terms and
     * kappa_4, kappa_5 the tangential terms (p1, p2). Its coordinates are not OpenCV's: each axis is
     * normalised to 1 at the image edge farthest from the optical centre, instead of by the focal
     * length. With x_i = s x' (x' = OpenCV's normalised coordinate, s = f / R) the radial terms pick
     * up s^2, s^4, s^6 and the tangential ones s. The two axes' normalisers differ (4:3 sensor), which
     * OpenCV's model cannot hold: s is their geometric mean, an approximation the key's deprecation
     * ("inconsistently defined") makes unavoidable.
     *
     * @param kappa        the six Camera2 values, or null
     * @param fxPx         focal length in the pre-correction array's pixels (x)
     * @param fyPx         focal length (y)
     * @param halfWidthPx  distance from the principal point to the farther left/right array edge, px
     * @param halfHeightPx distance from the principal point to the farther top/bottom array edge, px
     * @return OpenCV's five coefficients; empty when absent or all zero
     */
    public static double[] fromRadialDistortion(double[] kappa, double fxPx, double fyPx, double halfWidthPx,
                                                double halfHeightPx) {
        if (kappa == null) {
            return new double[0];
        }
        if (kappa.length != 6) {
            throw new IllegalArgumentException("LENS_RADIAL_DISTORTION must hold 6 values [kappa_0 .. kappa_5], got "
                    + kappa.length);
        }
        if (isZero(kappa, "LENS_RADIAL_DISTORTION")) {
            return new double[0];
        }
        if (Math.abs(kappa[0] - 1) > 0.05) {
            throw new IllegalArgumentException("LENS_RADIAL_DISTORTION kappa_0 is " + kappa[0]
                    + ", not 1: it would rescale the image, which the model cannot hold");
        }
        if (!(fxPx > 0 && fyPx > 0 && halfWidthPx > 0 && halfHeightPx > 0)) {
            throw new IllegalArgumentException("LENS_RADIAL_DISTORTION needs a positive focal length and array size");
        }
        double s = Math.sqrt(fxPx / halfWidthPx * (fyPx / halfHeightPx));
        double s2 = s * s;
        return new double[] {kappa[1] * s2, kappa[2] * s2 * s2, kappa[4] * s, kappa[5] * s, kappa[3] * s2 * s2 * s2};
    }

    private static boolean isZero(double[] v, String key) {
        boolean allZero = true;
        for (double x : v) {
            if (Double.isNaN(x) || Double.isInfinite(x)) {
                throw new IllegalArgumentException(key + " holds a non-finite value");
            }
            allZero &= x == 0;
        }
        return allZero;
    }

    private static double[] toDoubles(float[] v) {
        if (v == null) {
            return null;
        }
        double[] out = new double[v.length];
        for (int i = 0; i < v.length; i++) {
            out[i] = v[i];
        }
        return out;
    }
}
