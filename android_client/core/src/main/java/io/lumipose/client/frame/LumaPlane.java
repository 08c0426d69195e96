package io.lumipose.client.frame;

import java.nio.ByteBuffer;

/** The Y plane of a YUV_420_888 image copied into a packed width x height array. */
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
        ByteBuffer src = plane.duplicate();
        int base = src.position();
        if (src.remaining() < needed) {
            throw new IllegalArgumentException("Y plane holds " + src.remaining() + " bytes, " + width + "x" + height
                    + " at row_stride " + rowStride + " needs " + needed);
        }
        byte[] out = new byte[width * height];
        for (int row = 0; row < height; row++) {
            int start = base + row * rowStride;
            if (pixelStride == 1) {
                src.position(start);
                src.get(out, row * width, width);
            } else {
                for (int col = 0; col < width; col++) {
                    out[row * width + col] = src.get(start + col * pixelStride);
                }
            }
        }
        return out;
    }
}
