package io.lumipose.client.camera;

/** Camera2's {@code LENS_DISTORTION} turned into OpenCV's coefficient order. */
public final class LensDistortion {
    private LensDistortion() {
    }

    /**
     * Camera2 (API 28) gives [k1, k2, k3, p1, p2] (three radial, then two tangential);
     * OpenCV wants (k1, k2, p1, p2, k3).
     *
     * @param camera2 the five Camera2 coefficients, or null when the key is absent
     * @return OpenCV's five coefficients; empty when absent or all zero (no distortion)
     */
    public static double[] toOpenCv(float[] camera2) {
        if (camera2 == null) {
            return new double[0];
        }
        if (camera2.length != 5) {
            throw new IllegalArgumentException("LENS_DISTORTION must hold 5 values [k1, k2, k3, p1, p2], got "
                    + camera2.length);
        }
        boolean allZero = true;
        for (float v : camera2) {
            if (Float.isNaN(v) || Float.isInfinite(v)) {
                throw new IllegalArgumentException("LENS_DISTORTION holds a non-finite value");
            }
            allZero &= v == 0f;
        }
        if (allZero) {
            return new double[0];
        }
        return new double[] {camera2[0], camera2[1], camera2[3], camera2[4], camera2[2]};
    }
}
