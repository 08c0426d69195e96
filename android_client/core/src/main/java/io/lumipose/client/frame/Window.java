package io.lumipose.client.frame;

/** A rectangle of a frame's pixels: columns [x0, x1), rows [y0, y1). */
public final class Window {
    public final int x0;
    public final int y0;
    public final int x1;
    public final int y1;

    public Window(int x0, int y0, int x1, int y1) {
        if (x0 < 0 || y0 < 0 || x1 <= x0 || y1 <= y0) {
            throw new IllegalArgumentException("empty or negative window (" + x0 + ", " + y0 + ", " + x1 + ", " + y1
                    + ")");
        }
        this.x0 = x0;
        this.y0 = y0;
        this.x1 = x1;
        this.y1 = y1;
    }

    public int width() {
        return x1 - x0;
    }

    public int height() {
        return y1 - y0;
    }

    /** True when the window lies inside a width x height frame. */
    public boolean fitsIn(int width, int height) {
        return x1 <= width && y1 <= height;
    }

    /**
     * This window grown by {@code columns} of its width left and right and {@code rows} of its
     * height above and below, clipped to a width x height frame.
     */
    public Window grown(double columns, double rows, int width, int height) {
        int dx = (int) Math.ceil(columns * width());
        int dy = (int) Math.ceil(rows * height());
        return new Window(Math.max(0, x0 - dx), Math.max(0, y0 - dy), Math.min(width, x1 + dx),
                Math.min(height, y1 + dy));
    }

    /** True when {@code w} lies inside this window. */
    public boolean contains(Window w) {
        return w.x0 >= x0 && w.y0 >= y0 && w.x1 <= x1 && w.y1 <= y1;
    }

    /** True when the window is the whole width x height frame. */
    public boolean isWhole(int width, int height) {
        return x0 == 0 && y0 == 0 && x1 == width && y1 == height;
    }

    @Override
    public boolean equals(Object o) {
        if (!(o instanceof Window)) {
            return false;
        }
        Window w = (Window) o;
        return x0 == w.x0 && y0 == w.y0 && x1 == w.x1 && y1 == w.y1;
    }

    @Override
    public int hashCode() {
        return ((x0 * 31 + y0) * 31 + x1) * 31 + y1;
    }

    @Override
    public String toString() {
        return "(" + x0 + ", " + y0 + ", " + x1 + ", " + y1 + ")";
    }
}
