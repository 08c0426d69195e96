package io.lumipose.client.frame;

import java.nio.ByteBuffer;
import java.util.Arrays;

import io.lumipose.client.protocol.CaptureProtocol;

/**
 * The window to upload around the brightest panel of a Y plane: a port of
 * {@code lumipose_client/crop.py}'s {@code beacon_window}, giving the same window on the same
 * pixels (BeaconWindowTest runs both).
 *
 * <ol>
 * <li>A coarse view: the mean of each square block, a {@code BLOCK_DIVISOR}-th of the short side.
 * <li>A level half-way between the background (the view's median) and the plateau (its brightest
 *     block); no window when the two are less than {@code MIN_CONTRAST_DN} apart.
 * <li>The 8-connected bright region holding the brightest block, its box grown by
 *     {@code EDGE_BLOCKS} blocks (the blurred edge and glow stay below the level) and
 *     {@code EDGE_PX} pixels (the server's own margin around the panel) a side.
 * <li>A square {@code WINDOW_PER_PANEL} times that extent's longer side around its centre, clipped.
 * </ol>
 *
 * The coarse view is read straight from the plane (one row at a time): nothing of the frame is
 * copied but the window itself, later ({@link LumaPlane#copyWindow}).
 */
public final class BeaconWindow {
    // crop.py's constants, from the one protocol file both read
    static final double WINDOW_PER_PANEL = CaptureProtocol.WINDOW_PER_PANEL;
    static final int BLOCK_DIVISOR = CaptureProtocol.WINDOW_BLOCK_DIVISOR;
    static final double MIN_CONTRAST_DN = CaptureProtocol.WINDOW_MIN_CONTRAST_DN;
    static final int EDGE_BLOCKS = CaptureProtocol.WINDOW_EDGE_BLOCKS;
    /** The server's own margin around the panel (shared_schemas.windows.ROI_MARGIN_PX). */
    static final int EDGE_PX = CaptureProtocol.WINDOW_EDGE_PX;

    private BeaconWindow() {
    }

    /** The window around the brightest panel of a packed width x height plane, or null. */
    public static Window find(byte[] packed, int width, int height) {
        return find(ByteBuffer.wrap(packed), width, height, width, 1);
    }

    /**
     * The window around the brightest panel, or null when nothing stands out of the background.
     * Rows start {@code rowStride} bytes apart from the buffer's position, samples {@code pixelStride};
     * the buffer's position is not changed.
     */
    public static Window find(ByteBuffer plane, int width, int height, int rowStride, int pixelStride) {
        LumaPlane.checkLayout(plane, width, height, rowStride, pixelStride);
        int block = Math.max(1, Math.min(width, height) / BLOCK_DIVISOR);
        int rows = height / block;
        int cols = width / block;
        int[] sums = blockSums(plane, block, rows, cols, rowStride, pixelStride);
        double area = (double) block * block;

        int brightest = 0;
        for (int i = 1; i < sums.length; i++) {
            if (sums[i] > sums[brightest]) {
                brightest = i; // the first of equals, as numpy's argmax
            }
        }
        double plateau = sums[brightest] / area;
        double background = median(sums, area);
        if (plateau - background < MIN_CONTRAST_DN) {
            return null;
        }
        int[] box = regionBox(sums, rows, cols, brightest, (background + plateau) / 2, area);
        int top0 = box[0];
        int left0 = box[1];
        int bottom0 = box[2];
        int right0 = box[3];
        // a region at the view's far edge may go on in the rows and columns the view left out
        int margin = EDGE_BLOCKS * block + EDGE_PX;
        int left = left0 * block - margin;
        int top = top0 * block - margin;
        int right = right0 == cols - 1 ? width : (right0 + 1) * block + margin;
        int bottom = bottom0 == rows - 1 ? height : (bottom0 + 1) * block + margin;
        double centreX = (left + right) / 2.0;
        double centreY = (top + bottom) / 2.0;
        double half = WINDOW_PER_PANEL * Math.max(right - left, bottom - top) / 2;
        // (int) truncates toward zero as Python's int() does
        int x0 = Math.max(0, (int) (centreX - half));
        int y0 = Math.max(0, (int) (centreY - half));
        int x1 = Math.min(width, (int) Math.ceil(centreX + half));
        int y1 = Math.min(height, (int) Math.ceil(centreY + half));
        return new Window(x0, y0, x1, y1);
    }

    /** Sum of each whole block x block tile, row-major; the partial last tiles are left out. */
    private static int[] blockSums(ByteBuffer plane, int block, int rows, int cols, int rowStride, int pixelStride) {
        ByteBuffer src = plane.duplicate();
        int base = plane.position();
        int samples = cols * block;
        byte[] row = new byte[(samples - 1) * pixelStride + 1];
        int[] columns = new int[samples]; // each pixel column's sum over the block row so far
        int[] sums = new int[rows * cols];
        for (int r = 0; r < rows * block; r++) {
            src.position(base + r * rowStride);
            src.get(row);
            if (pixelStride == 1) {
                for (int i = 0; i < samples; i++) { // the hot loop: plain and vectorisable
                    columns[i] += row[i] & 0xff;
                }
            } else {
                for (int i = 0; i < samples; i++) {
                    columns[i] += row[i * pixelStride] & 0xff;
                }
            }
            if (r % block == block - 1) {
                int cell = (r / block) * cols;
                for (int i = 0; i < samples; i++) {
                    sums[cell + i / block] += columns[i];
                }
                Arrays.fill(columns, 0);
            }
        }
        return sums;
    }

    /** numpy's median of the block means: the middle one, or the mean of the middle two. */
    private static double median(int[] sums, double area) {
        int[] sorted = sums.clone();
        Arrays.sort(sorted);
        int n = sorted.length;
        if (n % 2 == 1) {
            return sorted[n / 2] / area;
        }
        return (sorted[n / 2 - 1] / area + sorted[n / 2] / area) / 2;
    }

    /** {top, left, bottom, right} block of the 8-connected region at or above the level holding the seed. */
    private static int[] regionBox(int[] sums, int rows, int cols, int seed, double level, double area) {
        boolean[] seen = new boolean[sums.length];
        int[] stack = new int[sums.length];
        int size = 0;
        stack[size++] = seed;
        seen[seed] = true;
        int top = rows;
        int left = cols;
        int bottom = -1;
        int right = -1;
        while (size > 0) {
            int cell = stack[--size];
            int r = cell / cols;
            int c = cell % cols;
            top = Math.min(top, r);
            bottom = Math.max(bottom, r);
            left = Math.min(left, c);
            right = Math.max(right, c);
            for (int nr = Math.max(0, r - 1); nr <= Math.min(rows - 1, r + 1); nr++) {
                for (int nc = Math.max(0, c - 1); nc <= Math.min(cols - 1, c + 1); nc++) {
                    int n = nr * cols + nc;
                    if (!seen[n] && sums[n] / area >= level) {
                        seen[n] = true;
                        stack[size++] = n;
                    }
                }
            }
        }
        return new int[] {top, left, bottom, right};
    }
}
