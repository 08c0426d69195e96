package io.lumipose.client.calibration;

import java.util.List;

/**
 * Which parts of the image the board's corners have covered so far: a grid of rows x columns over
 * the photo, each cell counting the corners seen in it, as the report's {@code coverage_cells}
 * (rows top to bottom) counts them, and {@link #coverage()} the share of cells holding at least
 * {@link #MIN_CELL_CORNERS}. A calibration pins the distortion down only where corners were seen,
 * so the screen shows the cells still to fill.
 *
 * <p>The grid is the server's (server/calibration, {@code CalibrationRules}: 6 cells along the
 * image's longer side, 4 along the shorter, a cell counts with 3 corners), and after a report the
 * report's own shape.
 */
public final class BoardCoverage {
    /** Cells along the longer side of the image before a report says otherwise. */
    public static final int LONG_SIDE_CELLS = 6;
    /** Cells along the shorter side. */
    public static final int SHORT_SIDE_CELLS = 4;
    /** Corners a cell needs to count as covered. */
    public static final int MIN_CELL_CORNERS = 3;
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
        return width >= height ? new BoardCoverage(width, height, SHORT_SIDE_CELLS, LONG_SIDE_CELLS)
                : new BoardCoverage(width, height, LONG_SIDE_CELLS, SHORT_SIDE_CELLS);
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

    /** Whether the cell holds {@link #MIN_CELL_CORNERS} or more corners. */
    public boolean covered(int row, int column) {
        return counts[row][column] >= MIN_CELL_CORNERS;
    }

    /** The share of cells holding {@link #MIN_CELL_CORNERS} or more corners, in [0, 1]. */
    public double coverage() {
        int covered = 0;
        for (int r = 0; r < rows; r++) {
            for (int c = 0; c < columns; c++) {
                if (covered(r, c)) {
                    covered++;
                }
            }
        }
        return (double) covered / (rows * columns);
    }
}
