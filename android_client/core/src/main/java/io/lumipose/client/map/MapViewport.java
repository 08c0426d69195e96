package io.lumipose.client.map;

import java.util.List;

/**
 * Fits a floor-plan area into a view: one scale for both axes, map +Y drawn upwards (screen y
 * grows downwards), the area centred, with a margin in pixels.
 */
public final class MapViewport {
    public final double minXM;
    public final double minYM;
    public final double pxPerM;
    private final double offsetXPx;
    private final double offsetYPx;
    private final double viewHeightPx;

    private MapViewport(double minXM, double minYM, double pxPerM, double offsetXPx, double offsetYPx,
                        double viewHeightPx) {
        this.minXM = minXM;
        this.minYM = minYM;
        this.pxPerM = pxPerM;
        this.offsetXPx = offsetXPx;
        this.offsetYPx = offsetYPx;
        this.viewHeightPx = viewHeightPx;
    }

    /**
     * @param map      beacons that must be visible
     * @param track    positions that should be visible too (may be empty)
     * @param minSpanM smallest area side shown, m (one beacon alone would otherwise fill the view)
     */
    public static MapViewport fit(RoomMap map, List<double[]> track, int viewWidthPx, int viewHeightPx,
                                  int marginPx, double minSpanM) {
        if (viewWidthPx <= 2 * marginPx || viewHeightPx <= 2 * marginPx) {
            throw new IllegalArgumentException("view " + viewWidthPx + "x" + viewHeightPx + " too small for margin "
                    + marginPx);
        }
        double minX = Double.POSITIVE_INFINITY;
        double minY = Double.POSITIVE_INFINITY;
        double maxX = Double.NEGATIVE_INFINITY;
        double maxY = Double.NEGATIVE_INFINITY;
        for (Beacon b : map.beacons) {
            for (double[] c : b.cornersXyM()) {
                minX = Math.min(minX, c[0]);
                maxX = Math.max(maxX, c[0]);
                minY = Math.min(minY, c[1]);
                maxY = Math.max(maxY, c[1]);
            }
        }
        for (double[] p : track) {
            minX = Math.min(minX, p[0]);
            maxX = Math.max(maxX, p[0]);
            minY = Math.min(minY, p[1]);
            maxY = Math.max(maxY, p[1]);
        }
        double spanX = Math.max(maxX - minX, minSpanM);
        double spanY = Math.max(maxY - minY, minSpanM);
        double midX = (minX + maxX) / 2;
        double midY = (minY + maxY) / 2;
        double usableW = viewWidthPx - 2.0 * marginPx;
        double usableH = viewHeightPx - 2.0 * marginPx;
        double scale = Math.min(usableW / spanX, usableH / spanY);
        double left = midX - usableW / scale / 2;
        double bottom = midY - usableH / scale / 2;
        return new MapViewport(left, bottom, scale, marginPx, marginPx, viewHeightPx);
    }

    /** Screen x, px, of map x, m. */
    public double screenX(double xM) {
        return offsetXPx + (xM - minXM) * pxPerM;
    }

    /** Screen y, px, of map y, m (map +Y up on screen). */
    public double screenY(double yM) {
        return viewHeightPx - offsetYPx - (yM - minYM) * pxPerM;
    }
}
