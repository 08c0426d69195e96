package io.lumipose.client.map;

/**
 * One ceiling panel of the map (docs/contract.md, "Panel shapes"): centre (m, map frame), yaw about
 * +Z (deg) and its outline, a rounded rectangle (a square by default) or a circle. The width runs
 * along the beacon frame's x_B axis, the map's X turned by the yaw; the height along y_B.
 */
public final class Beacon {
    /** The contract's {@code PanelShape} values. */
    public static final String ROUNDED_RECTANGLE = "rounded_rectangle";
    public static final String CIRCLE = "circle";

    public final int id;
    private final double[] centerM;
    public final double yawDeg;
    /** {@link #ROUNDED_RECTANGLE} or {@link #CIRCLE}. */
    public final String shape;
    /** Outer size along x_B, m: a square's side, a rectangle's width, a circle's diameter. */
    public final double widthM;
    /** Outer size along y_B, m: a square's side, a rectangle's height, a circle's diameter. */
    public final double heightM;
    /** A rounded rectangle's corner radius, m; 0 for a circle (it has no corners). */
    public final double cornerRadiusM;

    /** A square of side {@code sideM} with sharp corners. */
    public Beacon(int id, double[] centerM, double yawDeg, double sideM) {
        this(id, centerM, yawDeg, ROUNDED_RECTANGLE, sideM, sideM, 0);
    }

    private Beacon(int id, double[] centerM, double yawDeg, String shape, double widthM, double heightM,
                   double cornerRadiusM) {
        if (centerM == null || centerM.length != 3) {
            throw new IllegalArgumentException("center_m must hold 3 numbers");
        }
        if (!(widthM > 0) || !(heightM > 0)) {
            throw new IllegalArgumentException("a panel's sizes must be > 0, got " + widthM + " x " + heightM);
        }
        if (!(cornerRadiusM >= 0) || !(2 * cornerRadiusM < Math.min(widthM, heightM))) {
            throw new IllegalArgumentException("corner_radius_m must be in [0, half the shorter side), got "
                    + cornerRadiusM);
        }
        this.id = id;
        this.centerM = centerM.clone();
        this.yawDeg = yawDeg;
        this.shape = shape;
        this.widthM = widthM;
        this.heightM = heightM;
        this.cornerRadiusM = cornerRadiusM;
    }

    /** A rounded rectangle: {@code widthM} along x_B, {@code heightM} along y_B (equal for a square). */
    public static Beacon roundedRectangle(int id, double[] centerM, double yawDeg, double widthM, double heightM,
                                          double cornerRadiusM) {
        return new Beacon(id, centerM, yawDeg, ROUNDED_RECTANGLE, widthM, heightM, cornerRadiusM);
    }

    /** A round panel of diameter {@code diameterM}; its yaw changes nothing one can see. */
    public static Beacon circle(int id, double[] centerM, double yawDeg, double diameterM) {
        return new Beacon(id, centerM, yawDeg, CIRCLE, diameterM, diameterM, 0);
    }

    public double[] centerM() {
        return centerM.clone();
    }

    public boolean isCircle() {
        return CIRCLE.equals(shape);
    }

    /** A rounded rectangle has four corners, in the contract's order; a circle none. */
    public boolean hasCorners() {
        return !isCircle();
    }

    /** The longer outer size, m: the side, the width or the diameter. */
    public double sizeM() {
        return Math.max(widthM, heightM);
    }

    /** The radius of the outline's corner arcs, m: the corner radius, or half a circle's diameter. */
    public double outlineRadiusM() {
        return isCircle() ? widthM / 2 : cornerRadiusM;
    }

    /**
     * The four corners in the floor plane (x, y), m, of the rectangle the outline is rounded from (a
     * circle's: its circumscribing square): at yaw 0 the width runs along X and the height along Y.
     */
    public double[][] cornersXyM() {
        double w = widthM / 2;
        double h = heightM / 2;
        double[][] local = {{-w, -h}, {w, -h}, {w, h}, {-w, h}};
        double[][] out = new double[4][];
        for (int i = 0; i < 4; i++) {
            out[i] = toMapXy(local[i][0], local[i][1]);
        }
        return out;
    }

    /**
     * The outline in the floor plane (x, y), m, counter-clockwise seen from above: four corner arcs
     * of {@code pointsPerArc} points each (the straight sides are the chords between them), one point
     * per corner when the corners are sharp. A circle is four quarter arcs.
     */
    public double[][] outlineXyM(int pointsPerArc) {
        if (pointsPerArc < 2) {
            throw new IllegalArgumentException("pointsPerArc must be >= 2, got " + pointsPerArc);
        }
        double r = outlineRadiusM();
        int perArc = r == 0 ? 1 : pointsPerArc;
        double innerX = widthM / 2 - r;
        double innerY = heightM / 2 - r;
        double[][] signs = {{1, 1}, {-1, 1}, {-1, -1}, {1, -1}};
        double[][] out = new double[4 * perArc][];
        for (int k = 0; k < 4; k++) {
            double start = Math.PI / 2 * k;
            for (int i = 0; i < perArc; i++) {
                double a = perArc == 1 ? start : start + Math.PI / 2 * i / (perArc - 1);
                out[k * perArc + i] = toMapXy(signs[k][0] * innerX + r * Math.cos(a),
                        signs[k][1] * innerY + r * Math.sin(a));
            }
        }
        return out;
    }

    private double[] toMapXy(double xB, double yB) {
        double c = Math.cos(Math.toRadians(yawDeg));
        double s = Math.sin(Math.toRadians(yawDeg));
        return new double[] {centerM[0] + c * xB - s * yB, centerM[1] + s * xB + c * yB};
    }
}
