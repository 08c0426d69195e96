package io.lumipose.client.camera;

/**
 * Pinhole intrinsics of one output size in the contract's convention: OpenCV pixel coordinates,
 * pixel centres at integers (a centred principal point is ((w - 1) / 2, (h - 1) / 2)).
 * {@code distortion} is in OpenCV's order (k1, k2, p1, p2, k3), empty for none.
 */
public final class Intrinsics {
    public final double fx;
    public final double fy;
    public final double cx;
    public final double cy;
    private final double[] distortion;
    /** Pixel pitch at this output size, m; null when unknown. */
    public final Double pixelSizeM;
    public final Double focalLengthM;
    public final String device;

    public Intrinsics(double fx, double fy, double cx, double cy, double[] distortion,
                      Double pixelSizeM, Double focalLengthM, String device) {
        requireFinite("fx", fx);
        requireFinite("fy", fy);
        requireFinite("cx", cx);
        requireFinite("cy", cy);
        if (fx <= 0 || fy <= 0) {
            throw new IllegalArgumentException("camera.fx and camera.fy must be > 0, got " + fx + ", " + fy);
        }
        double[] d = distortion == null ? new double[0] : distortion.clone();
        for (int i = 0; i < d.length; i++) {
            requireFinite("distortion[" + i + "]", d[i]);
        }
        if (pixelSizeM != null && !(pixelSizeM > 0)) {
            throw new IllegalArgumentException("camera.pixel_size_m must be > 0, got " + pixelSizeM);
        }
        if (focalLengthM != null && !(focalLengthM > 0)) {
            throw new IllegalArgumentException("camera.focal_length_m must be > 0, got " + focalLengthM);
        }
        this.fx = fx;
        this.fy = fy;
        this.cx = cx;
        this.cy = cy;
        this.distortion = d;
        this.pixelSizeM = pixelSizeM;
        this.focalLengthM = focalLengthM;
        this.device = device;
    }

    public double[] distortion() {
        return distortion.clone();
    }

    private static void requireFinite(String field, double v) {
        if (Double.isNaN(v) || Double.isInfinite(v)) {
            throw new IllegalArgumentException("camera." + field + " must be a finite number, got " + v);
        }
    }
}
