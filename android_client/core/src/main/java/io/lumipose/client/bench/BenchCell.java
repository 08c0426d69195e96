package io.lumipose.client.bench;

/** One test-bench cell: grid indices, its label as stored with the sample, its position on the floor. */
public final class BenchCell {
    public final int xIndex;
    public final int yIndex;
    public final double cellSideM;

    public BenchCell(int xIndex, int yIndex, double cellSideM) {
        this.xIndex = xIndex;
        this.yIndex = yIndex;
        this.cellSideM = cellSideM;
    }

    /** "x,y" as the paper marks the cells, e.g. "-8,11". */
    public String label() {
        return xIndex + "," + yIndex;
    }

    /** The cell's point in the map frame, m (the grid centre is under the beacon, floor at 0). */
    public double[] positionM() {
        return new double[] {xIndex * cellSideM, yIndex * cellSideM, 0.0};
    }

    /** Horizontal distance between a located position and this cell, mm. */
    public double horizontalErrorMm(double[] locatedM) {
        double dx = locatedM[0] - xIndex * cellSideM;
        double dy = locatedM[1] - yIndex * cellSideM;
        return Math.sqrt(dx * dx + dy * dy) * 1000.0;
    }
}
