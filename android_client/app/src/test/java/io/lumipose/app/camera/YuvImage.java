package io.lumipose.app.camera;

import android.graphics.ImageFormat;
import android.media.Image;

import java.nio.ByteBuffer;

/**
 * A YUV_420_888 image as phones deliver it: a Y plane whose rows are padded past the width
 * (rowStride > width), and interleaved chroma planes (pixelStride 2). Knows whether it was closed.
 */
public final class YuvImage extends Image {
    private final int width;
    private final int height;
    private final long timestampNs;
    private final Plane[] planes;
    private volatile boolean closed;

    /** {@code luma[y * width + x]} becomes the Y plane, each row padded to {@code rowStride} with 0xEE. */
    public YuvImage(int width, int height, int rowStride, long timestampNs, byte[] luma) {
        if (rowStride < width || luma.length != width * height) {
            throw new IllegalArgumentException("bad image shape");
        }
        this.width = width;
        this.height = height;
        this.timestampNs = timestampNs;
        ByteBuffer y = ByteBuffer.allocateDirect(rowStride * (height - 1) + width);
        for (int row = 0; row < height; row++) {
            y.position(row * rowStride);
            y.put(luma, row * width, width);
            if (row < height - 1) {
                for (int pad = width; pad < rowStride; pad++) {
                    y.put((byte) 0xEE);
                }
            }
        }
        y.rewind();
        int chromaRow = rowStride;
        ByteBuffer uv = ByteBuffer.allocateDirect(chromaRow * (height / 2 - 1) + width - 1);
        planes = new Plane[] {new YuvPlane(y, rowStride, 1), new YuvPlane(uv, chromaRow, 2),
                new YuvPlane(uv.duplicate(), chromaRow, 2)};
    }

    @Override
    public int getFormat() {
        return ImageFormat.YUV_420_888;
    }

    @Override
    public int getWidth() {
        return width;
    }

    @Override
    public int getHeight() {
        return height;
    }

    @Override
    public long getTimestamp() {
        return timestampNs;
    }

    @Override
    public int getTransform() {
        return 0;
    }

    @Override
    public int getScalingMode() {
        return 0;
    }

    @Override
    public Plane[] getPlanes() {
        if (closed) {
            throw new IllegalStateException("Image is already closed");
        }
        return planes;
    }

    @Override
    public void close() {
        closed = true;
    }

    public boolean closed() {
        return closed;
    }

    private static final class YuvPlane extends Plane {
        private final ByteBuffer buffer;
        private final int rowStride;
        private final int pixelStride;

        YuvPlane(ByteBuffer buffer, int rowStride, int pixelStride) {
            this.buffer = buffer;
            this.rowStride = rowStride;
            this.pixelStride = pixelStride;
        }

        @Override
        public int getRowStride() {
            return rowStride;
        }

        @Override
        public int getPixelStride() {
            return pixelStride;
        }

        @Override
        public ByteBuffer getBuffer() {
            return buffer;
        }
    }
}
