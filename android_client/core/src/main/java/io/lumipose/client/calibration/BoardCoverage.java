package io.lumipose.client.calibration;

import java.util.List;

/**
 * Which parts of the image the board's corners have covered so far: a grid of rows x columns over
 * the photo, each cell counting the corners seen in it, as the report's {@code coverage_cells}
 * (rows top to bottom) and {@code coverage} (the share of cells holding a corner) say. A
 * calibration pins the distortion down only where corners were seen, so the screen shows the empty
 * cells to fill.
 *
 * <p>Until the server's report gives its grid, the grid has {@link #LONG_SIDE_CELLS} cells along the
 * image's longer side and as many square-ish cells along the shorter; after a report, its shape.
 */
public final class BoardCoverage {
    /** Cells along the longer side of the image before a report says otherwise. */
    public static final int LONG_SIDE_CELLS = 8;
    public final int width;
    public final int height;
    public final int rows;
    public final int columns;
    private final int[][] counts;

    /** An empty grid of {@code rows x columns} over a {@code width x height} image. */
    public BoardCoverage(int width, int height, int rows, int columns) {
        if (width < 1 || height < 1) {
            throw new IllegalArgumentException("image size must be positive, got " + width + "x" + height);
        }
        if (rows < 1 || columns < 1) {
            throw new IllegalArgumentException("grid must have at least one cell, got " + rows + "x" + columns);
        }
        this.width = width;
        this.height = height;
        this.rows = rows;
        this.columns = columns;
        this.counts = new int[rows][columns];
    }

    /** The default grid for an image: {@link #LONG_SIDE_CELLS} along its longer side. */
    public static BoardCoverage forImage(int width, int height) {
        int longer = Math.max(width, height);
        int shorter = Math.max(1, (int) Math.round(LONG_SIDE_CELLS * (double) Math.min(width, height) / longer));
        return width >= height ? new BoardCoverage(width, height, shorter, LONG_SIDE_CELLS)
                : new BoardCoverage(width, height, LONG_SIDE_CELLS, shorter);
    }

    /** A grid of the given shape holding every view's corners. */
    public static BoardCoverage of(List<BoardView> views, int width, int height, int rows, int columns) {
        BoardCoverage c = new BoardCoverage(width, height, rows, columns);
        for (BoardView v : views) {
            c.add(v);
        }
        return c;
    }

    /**
     * Counts the view's corners in their cells; a corner on or beyond the image's edge counts in
     * the edge's cell.
     *
     * @throws IllegalArgumentException when the view's photo is not this grid's image size
     */
    public void add(BoardView view) {
        if (view.width != width || view.height != height) {
            throw new IllegalArgumentException("photo '" + view.name + "' is " + view.width + "x" + view.height
                    + ", the others " + width + "x" + height);
        }
        for (int i = 0; i < view.corners(); i++) {
            double[] p = view.cornerPx(i);
            counts[cell(p[1], height, rows)][cell(p[0], width, columns)]++;
        }
    }

    /** The cell of coordinate v (pixel centres at integers; the image spans [-0.5, size - 0.5]). */
    private static int cell(double v, int size, int cells) {
        int c = (int) Math.floor((v + 0.5) * cells / size);
        return Math.max(0, Math.min(cells - 1, c));
    }

    /** Corners seen in the cell at {@code row}, {@code column} (row 0 at the top). */
    public int count(int row, int column) {
        return counts[row][column];
    }

    /** Corners per cell, rows top to bottom (a copy). */
    public int[][] counts() {
        int[][] out = new int[rows][];
        for (int r = 0; r < rows; r++) {
            out[r] = counts[r].clone();
        }
        return out;
    }

    /** The share of cells holding at least one corner, in [0, 1]. */
    public double coverage() {
        int covered = 0;
        for (int[] row : counts) {
            for (int n : row) {
                if (n > 0) {
                    covered++;
                }
            }
        }
        return (double) covered / (rows * columns);
    }
}
