package io.lumipose.client.frame;

import java.nio.ByteBuffer;

/**
 * A small grey picture of a Y plane for a screen that shows what the camera sees (the calibration
 * and survey screens draw their overlays on it): every {@code step}-th sample of every
 * {@code step}-th row, {@code step} the smallest that fits the longer side within the asked size.
 * Coordinates map back to the full frame by {@link #toFrameX}/{@link #toFrameY}.
 */
public final class GreyPreview {
    public final int width;
    public final int height;
    /** Frame pixels per preview pixel. */
    public final int step;
    public final int frameWidth;
    public final int frameHeight;
    private final byte[] pixels;

    private GreyPreview(int width, int height, int step, int frameWidth, int frameHeight, byte[] pixels) {
        this.width = width;
        this.height = height;
        this.step = step;
        this.frameWidth = frameWidth;
        this.frameHeight = frameHeight;
        this.pixels = pixels;
    }

    /**
     * @param maxSide the longest side the preview may have, px (>= 1)
     */
    public static GreyPreview of(ByteBuffer plane, int width, int height, int rowStride, int pixelStride,
                                 int maxSide) {
        if (maxSide < 1) {
            throw new IllegalArgumentException("maxSide must be >= 1, got " + maxSide);
        }
        LumaPlane.checkLayout(plane, width, height, rowStride, pixelStride);
        int step = (Math.max(width, height) + maxSide - 1) / maxSide;
        int w = (width + step - 1) / step;
        int h = (height + step - 1) / step;
        byte[] out = new byte[w * h];
        int base = plane.position();
        for (int y = 0; y < h; y++) {
            int row = base + y * step * rowStride;
            for (int x = 0; x < w; x++) {
                out[y * w + x] = plane.get(row + x * step * pixelStride);
            }
        }
        return new GreyPreview(w, h, step, width, height, out);
    }

    /** The picture as opaque ARGB, row after row (Android's Bitmap.createBitmap takes it as it is). */
    public int[] argb() {
        return argb(null);
    }

    /** {@link #argb()} into {@code reuse} when it is the right length (a view showing five a second keeps one). */
    public int[] argb(int[] reuse) {
        int[] out = reuse != null && reuse.length == pixels.length ? reuse : new int[pixels.length];
        for (int i = 0; i < out.length; i++) {
            int v = pixels[i] & 0xff;
            out[i] = 0xff000000 | v << 16 | v << 8 | v;
        }
        return out;
    }

    /** The mean grey level, DN: tells the screen when the board is too dark or too bright to find. */
    public double meanDn() {
        long sum = 0;
        for (byte p : pixels) {
            sum += p & 0xff;
        }
        return pixels.length == 0 ? 0 : (double) sum / pixels.length;
    }

    /** The full frame's column under preview column x (the column its sample came from). */
    public double toFrameX(double x) {
        return Math.max(0, Math.min(frameWidth - 1, x * step));
    }

    /** The full frame's row under preview row y. */
    public double toFrameY(double y) {
        return Math.max(0, Math.min(frameHeight - 1, y * step));
    }
}
