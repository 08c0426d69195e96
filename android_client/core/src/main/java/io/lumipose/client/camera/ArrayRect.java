package io.lumipose.client.camera;

/**
 * A rectangle of sensor pixels in pixel-array coordinates, like Camera2's
 * {@code SENSOR_INFO_ACTIVE_ARRAY_SIZE} and {@code SENSOR_INFO_PRE_CORRECTION_ACTIVE_ARRAY_SIZE}.
 */
public final class ArrayRect {
    public final int left;
    public final int top;
    public final int width;
    public final int height;

    public ArrayRect(int left, int top, int width, int height) {
        if (width <= 0 || height <= 0) {
            throw new IllegalArgumentException("array rectangle must have a positive size, got " + width + "x" + height);
        }
        this.left = left;
        this.top = top;
        this.width = width;
        this.height = height;
    }

    public static ArrayRect ofSize(int width, int height) {
        return new ArrayRect(0, 0, width, height);
    }

    @Override
    public boolean equals(Object o) {
        if (!(o instanceof ArrayRect)) {
            return false;
        }
        ArrayRect r = (ArrayRect) o;
        return r.left == left && r.top == top && r.width == width && r.height == height;
    }

    @Override
    public int hashCode() {
        return ((left * 31 + top) * 31 + width) * 31 + height;
    }

    /** As Camera2's JSON writes it: [left, top, width, height]. */
    @Override
    public String toString() {
        return "[" + left + ", " + top + ", " + width + ", " + height + "]";
    }
}
