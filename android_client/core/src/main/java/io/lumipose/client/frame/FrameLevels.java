package io.lumipose.client.frame;

import java.nio.ByteBuffer;

import io.lumipose.client.protocol.CaptureProtocol;

/**
 * A whole plane's background and plateau grey levels by the contract's coarse rule
 * ({@code shared_schemas/windows.py}, {@code frame_levels}), sent with a window as
 * {@code crop.levels_dn}: a tight window's own histogram is mostly panel, and with the whole
 * frame's levels the server reads the window as the whole frame (docs/contract.md, "Windows").
 *
 * <p>The rule: step = the short side / {@code COARSE_SHORT_SIDE_PX} (at least 1); the coarse view
 * is every step-th pixel of every step-th row, plus the last column and row where the grid misses
 * them; of its every other row, the background is the smallest grey level whose cumulative count
 * reaches half the samples, the plateau the smallest reaching (1 - {@code PLATEAU_FRACTION}) of them.
 * FrameLevelsTest compares it with the Python function on rendered frames.
 */
public final class FrameLevels {
    // shared_schemas/windows.py's constants, from the protocol file
    static final int COARSE_SHORT_SIDE_PX = CaptureProtocol.LEVELS_COARSE_SHORT_SIDE_PX;
    static final double PLATEAU_FRACTION = CaptureProtocol.LEVELS_PLATEAU_FRACTION;

    private FrameLevels() {
    }

    /** [background, plateau] of a width x height plane (rows rowStride bytes apart, samples pixelStride). */
    public static double[] measure(ByteBuffer plane, int width, int height, int rowStride, int pixelStride) {
        LumaPlane.checkLayout(plane, width, height, rowStride, pixelStride);
        int step = Math.max(1, Math.min(width, height) / COARSE_SHORT_SIDE_PX);
        int[] rows = viewLines(height, step);
        int[] columns = viewLines(width, step);
        long[] histogram = new long[256];
        int base = plane.position();
        for (int i = 0; i < rows.length; i += 2) { // every other row of the view is plenty for two quantiles
            int start = base + rows[i] * rowStride;
            for (int column : columns) {
                histogram[plane.get(start + column * pixelStride) & 0xff]++;
            }
        }
        return levels(histogram);
    }

    /** The view's lines across a side: 0, step, 2 step, ..., and the last one when the grid misses it. */
    static int[] viewLines(int size, int step) {
        int onGrid = (size - 1) / step + 1;
        boolean last = (size - 1) % step > 0;
        int[] lines = new int[onGrid + (last ? 1 : 0)];
        for (int i = 0; i < onGrid; i++) {
            lines[i] = i * step;
        }
        if (last) {
            lines[onGrid] = size - 1;
        }
        return lines;
    }

    /** numpy's searchsorted on the cumulative counts: whole counts against float64 fractions of the total. */
    static double[] levels(long[] histogram) {
        long total = 0;
        for (long count : histogram) {
            total += count;
        }
        double half = 0.5 * total;
        double top = (1.0 - PLATEAU_FRACTION) * total;
        int background = -1;
        long cumulative = 0;
        for (int level = 0; level < 256; level++) {
            cumulative += histogram[level];
            if (background < 0 && cumulative >= half) {
                background = level;
            }
            if (cumulative >= top) {
                return new double[] {background, level};
            }
        }
        throw new IllegalStateException("no samples");
    }
}
