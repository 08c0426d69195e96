package io.lumipose.client.camera;

/** A width x height in pixels. */
public final class PixelSize {
    public final int width;
    public final int height;

    public PixelSize(int width, int height) {
        if (width <= 0 || height <= 0) {
            throw new IllegalArgumentException("size must be positive, got " + width + "x" + height);
        }
        this.width = width;
        this.height = height;
    }

    public long pixels() {
        return (long) width * height;
    }

    @Override
    public boolean equals(Object o) {
        return o instanceof PixelSize && ((PixelSize) o).width == width && ((PixelSize) o).height == height;
    }

    @Override
    public int hashCode() {
        return width * 31 + height;
    }

    @Override
    public String toString() {
        return width + "x" + height;
    }
}
