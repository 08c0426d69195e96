package io.lumipose.client.bench;

import java.util.ArrayList;
import java.util.Collections;
import java.util.List;

/**
 * The paper's test bench (Section II-B): cells of 0.05 m, x from -8 to 8 left to right, y from 11
 * to -11 top to bottom, walked row by row from (-8, 11) to (8, -11): 17 x 23 = 391 samples.
 */
public final class TestBenchGrid {
    public final List<BenchCell> cells;

    public TestBenchGrid(int xMax, int yMax, double cellSideM) {
        if (xMax < 0 || yMax < 0 || !(cellSideM > 0)) {
            throw new IllegalArgumentException("grid needs xMax, yMax >= 0 and cellSideM > 0");
        }
        List<BenchCell> list = new ArrayList<BenchCell>();
        for (int y = yMax; y >= -yMax; y--) {
            for (int x = -xMax; x <= xMax; x++) {
                list.add(new BenchCell(x, y, cellSideM));
            }
        }
        this.cells = Collections.unmodifiableList(list);
    }

    public static TestBenchGrid paper() {
        return new TestBenchGrid(8, 11, 0.05);
    }

    public int size() {
        return cells.size();
    }

    public BenchCell cell(int index) {
        return cells.get(index);
    }

    /** Index of the cell with this label, or -1. */
    public int indexOf(String label) {
        for (int i = 0; i < cells.size(); i++) {
            if (cells.get(i).label().equals(label)) {
                return i;
            }
        }
        return -1;
    }
}
