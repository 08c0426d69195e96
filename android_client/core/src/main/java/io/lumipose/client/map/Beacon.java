package io.lumipose.client.map;

/** One ceiling panel of the map: centre (m, map frame), yaw about +Z (deg), side (m). */
public final class Beacon {
    public final int id;
    private final double[] centerM;
    public final double yawDeg;
    public final double sideM;

    public Beacon(int id, double[] centerM, double yawDeg, double sideM) {
        if (centerM == null || centerM.length != 3) {
            throw new IllegalArgumentException("center_m must hold 3 numbers");
        }
        if (!(sideM > 0)) {
            throw new IllegalArgumentException("side_m must be > 0, got " + sideM);
        }
        this.id = id;
        this.centerM = centerM.clone();
        this.yawDeg = yawDeg;
        this.sideM = sideM;
    }

    public double[] centerM() {
        return centerM.clone();
    }

    /** The four corners in the floor plane (x, y), m: at yaw 0 the edges run along X and Y. */
    public double[][] cornersXyM() {
        double h = sideM / 2;
        double c = Math.cos(Math.toRadians(yawDeg));
        double s = Math.sin(Math.toRadians(yawDeg));
        double[][] local = {{-h, -h}, {h, -h}, {h, h}, {-h, h}};
        double[][] out = new double[4][];
        for (int i = 0; i < 4; i++) {
            out[i] = new double[] {centerM[0] + c * local[i][0] - s * local[i][1],
                centerM[1] + s * local[i][0] + c * local[i][1]};
        }
        return out;
    }
}
