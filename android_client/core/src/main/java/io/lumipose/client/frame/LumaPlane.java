package io.lumipose.client.frame;

import java.nio.ByteBuffer;

/** The Y plane of a YUV_420_888 image (or a window of it) copied into a packed array. */
public final class LumaPlane {
    private LumaPlane() {
    }

    /**
     * Copies {@code height} rows of {@code width} luma samples out of a plane buffer.
     *
     * <p>Rows start {@code rowStride} bytes apart and samples {@code pixelStride} bytes apart.
     * The buffer may end right after the last row's last sample (no padding after it), so only
     * (height - 1) * rowStride + (width - 1) * pixelStride + 1 bytes are required. The buffer's
     * position is not changed.
     *
     * @return width * height bytes, row after row (row_stride = width)
     */
    public static byte[] copy(ByteBuffer plane, int width, int height, int rowStride, int pixelStride) {
        return copyWindow(plane, width, height, rowStride, pixelStride, new Window(0, 0, width, height));
    }

    /**
     * Copies only the window's samples out of a width x height plane laid out as in
     * {@link #copy}: window.width() * window.height() bytes, row after row.
     */
    public static byte[] copyWindow(ByteBuffer plane, int width, int height, int rowStride, int pixelStride,
                                    Window window) {
        checkLayout(plane, width, height, rowStride, pixelStride);
        if (!window.fitsIn(width, height)) {
            throw new IllegalArgumentException("window " + window + " outside the " + width + "x" + height + " plane");
        }
        ByteBuffer src = plane.duplicate();
        int base = plane.position();
        int w = window.width();
        byte[] out = new byte[w * window.height()];
        for (int row = 0; row < window.height(); row++) {
            int start = base + (window.y0 + row) * rowStride + window.x0 * pixelStride;
            if (pixelStride == 1) {
                src.position(start);
                src.get(out, row * w, w);
            } else {
                for (int col = 0; col < w; col++) {
                    out[row * w + col] = src.get(start + col * pixelStride);
                }
            }
        }
        return out;
    }

    /** Refuses a layout the buffer cannot hold. */
    static void checkLayout(ByteBuffer plane, int width, int height, int rowStride, int pixelStride) {
        if (width <= 0 || height <= 0) {
            throw new IllegalArgumentException("width and height must be > 0, got " + width + "x" + height);
        }
        if (pixelStride <= 0) {
            throw new IllegalArgumentException("pixel_stride must be > 0, got " + pixelStride);
        }
        long rowBytes = (long) (width - 1) * pixelStride + 1;
        if (rowStride < rowBytes) {
            throw new IllegalArgumentException("row_stride " + rowStride + " is shorter than a row of " + width
                    + " samples at pixel stride " + pixelStride);
        }
        long needed = (long) (height - 1) * rowStride + rowBytes;
        if (plane.remaining() < needed) {
            throw new IllegalArgumentException("Y plane holds " + plane.remaining() + " bytes, " + width + "x"
                    + height + " at row_stride " + rowStride + " needs " + needed);
        }
    }
}
