package io.lumipose.client.calibration;

import java.util.Locale;

import io.lumipose.client.map.Beacon;
import io.lumipose.client.net.LocateResult;

/**
 * Calibration mode (paper Fig. 2b): the camera's optical axis must point straight up through the
 * beacon centre before the grid is anchored. From a locate result it tells how far the camera is
 * off in the floor plane and how much it is tilted, and which way to move it.
 */
public final class AlignmentGuide {
    private final double toleranceM;
    private final double tiltToleranceDeg;

    public AlignmentGuide(double toleranceM, double tiltToleranceDeg) {
        if (!(toleranceM > 0) || !(tiltToleranceDeg > 0)) {
            throw new IllegalArgumentException("tolerances must be > 0");
        }
        this.toleranceM = toleranceM;
        this.tiltToleranceDeg = tiltToleranceDeg;
    }

    /** What the screen shows for one result. */
    public static final class Alignment {
        public final boolean located;
        public final boolean aligned;
        /** Camera minus beacon centre in the map's X and Y, m. */
        public final double offsetXM;
        public final double offsetYM;
        /** Angle between the optical axis and straight up, deg. */
        public final double tiltDeg;
        public final String hint;

        Alignment(boolean located, boolean aligned, double offsetXM, double offsetYM, double tiltDeg, String hint) {
            this.located = located;
            this.aligned = aligned;
            this.offsetXM = offsetXM;
            this.offsetYM = offsetYM;
            this.tiltDeg = tiltDeg;
            this.hint = hint;
        }
    }

    public Alignment evaluate(LocateResult result, Beacon beacon) {
        if (!result.ok) {
            return new Alignment(false, false, Double.NaN, Double.NaN, Double.NaN,
                    "No fix (" + result.reason + "): bring the whole panel into view.");
        }
        double[] p = result.positionM();
        double[] c = beacon.centerM();
        double dx = p[0] - c[0];
        double dy = p[1] - c[1];
        double tilt = Double.NaN;
        double[][] r = result.rotationWc();
        if (r != null) {
            // Optical axis (camera +z) in the map frame is R_wc's third column; straight up is +Z.
            tilt = Math.toDegrees(Math.acos(Math.max(-1, Math.min(1, r[2][2]))));
        }
        boolean centred = Math.hypot(dx, dy) <= toleranceM;
        boolean level = !Double.isNaN(tilt) && tilt <= tiltToleranceDeg;
        StringBuilder hint = new StringBuilder();
        if (!centred) {
            hint.append(String.format(Locale.US, "Move %.1f mm %s and %.1f mm %s. ", Math.abs(dx) * 1000,
                    dx > 0 ? "towards -X" : "towards +X", Math.abs(dy) * 1000, dy > 0 ? "towards -Y" : "towards +Y"));
        }
        if (!level) {
            hint.append(Double.isNaN(tilt) ? "Tilt unknown. "
                    : String.format(Locale.US, "Level the phone: tilted %.2f deg. ", tilt));
        }
        if (centred && level) {
            hint.append("Aligned: the optical axis is under the beacon centre. Anchor the grid.");
        }
        return new Alignment(true, centred && level, dx, dy, tilt, hint.toString().trim());
    }
}
