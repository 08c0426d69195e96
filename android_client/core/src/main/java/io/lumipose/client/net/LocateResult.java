package io.lumipose.client.net;

import java.util.Collections;
import java.util.List;

import org.json.JSONObject;

import io.lumipose.client.json.ContractException;
import io.lumipose.client.json.Json;

/** The contract's result JSON ({@code lumipose.result/1}): a fix, or a refusal with a reason. */
public final class LocateResult {
    public static final String SCHEMA = "lumipose.result/1";
    /**
     * The chi-square quantile of 2 degrees of freedom at 95 %: the XY block of the position's
     * covariance scaled by it is the 95 % error ellipse on the floor plan (docs/contract.md, "Uncertainty").
     */
    public static final double CHI2_2DOF_95 = 5.991;

    public final boolean ok;
    private final double[] positionM;
    private final double[][] rotationWc;
    private final double[] yawPitchRollDeg;
    public final Integer beaconId;
    public final String beaconIdSource;
    public final String orientationRule;
    private final double[] centerPx;
    public final Double reprojectionErrorPx;
    public final boolean gravityUsed;
    private final double[] positionSigmaM;
    private final double[][] positionCovarianceM2;
    /** Machine-readable refusal, e.g. {@code no_beacon}; null on success. */
    public final String reason;
    public final String message;
    public final List<String> warnings;

    private LocateResult(boolean ok, double[] positionM, double[][] rotationWc, double[] yawPitchRollDeg,
                         Integer beaconId, String beaconIdSource, String orientationRule, double[] centerPx,
                         Double reprojectionErrorPx, boolean gravityUsed, double[] positionSigmaM,
                         double[][] positionCovarianceM2, String reason, String message, List<String> warnings) {
        this.ok = ok;
        this.positionM = positionM;
        this.rotationWc = rotationWc;
        this.yawPitchRollDeg = yawPitchRollDeg;
        this.beaconId = beaconId;
        this.beaconIdSource = beaconIdSource;
        this.orientationRule = orientationRule;
        this.centerPx = centerPx;
        this.reprojectionErrorPx = reprojectionErrorPx;
        this.gravityUsed = gravityUsed;
        this.positionSigmaM = positionSigmaM;
        this.positionCovarianceM2 = positionCovarianceM2;
        this.reason = reason;
        this.message = message;
        this.warnings = Collections.unmodifiableList(warnings);
    }

    /** Camera optical centre in the map frame, m; null when not ok. */
    public double[] positionM() {
        return positionM == null ? null : positionM.clone();
    }

    public double[][] rotationWc() {
        return copy(rotationWc);
    }

    /** R_wc = Rz(yaw) Ry(pitch) Rx(roll), degrees; all zero = looking straight up. */
    public double[] yawPitchRollDeg() {
        return yawPitchRollDeg == null ? null : yawPitchRollDeg.clone();
    }

    public double[] centerPx() {
        return centerPx == null ? null : centerPx.clone();
    }

    /**
     * 1-sigma uncertainty of {@link #positionM()} along the map's X, Y, Z, m: the square roots of the
     * covariance's diagonal. Null on a refusal, and from a server that does not give it.
     */
    public double[] positionSigmaM() {
        return positionSigmaM == null ? null : positionSigmaM.clone();
    }

    /** Covariance of {@link #positionM()} in the map frame (rows and columns X, Y, Z), m^2; null as the sigmas. */
    public double[][] positionCovarianceM2() {
        return copy(positionCovarianceM2);
    }

    /**
     * The 95 % error ellipse of the position on the floor plan, from the covariance's XY block:
     * {semi-major axis m, semi-minor axis m, direction of the major axis in deg counter-clockwise
     * from +X, in (-90, 90]}; null without a covariance.
     */
    public double[] errorEllipse95XyM() {
        if (positionCovarianceM2 == null) {
            return null;
        }
        double a = positionCovarianceM2[0][0];
        double b = (positionCovarianceM2[0][1] + positionCovarianceM2[1][0]) / 2;
        double d = positionCovarianceM2[1][1];
        double mean = (a + d) / 2;
        double half = Math.hypot((a - d) / 2, b);
        double major = Math.sqrt(CHI2_2DOF_95 * Math.max(mean + half, 0));
        double minor = Math.sqrt(CHI2_2DOF_95 * Math.max(mean - half, 0));
        double angle = Math.toDegrees(0.5 * Math.atan2(2 * b, a - d));
        return new double[] {major, minor, angle == -90 ? 90 : angle};
    }

    private static double[][] copy(double[][] rows) {
        if (rows == null) {
            return null;
        }
        double[][] out = new double[rows.length][];
        for (int i = 0; i < rows.length; i++) {
            out[i] = rows[i].clone();
        }
        return out;
    }

    public static LocateResult fromJson(String text) {
        return fromJson(Json.parseObject(text, "result"));
    }

    public static LocateResult fromJson(JSONObject o) {
        Json.checkSchema(o, SCHEMA);
        Boolean ok = Json.optBoolean(o, "ok", "ok");
        if (ok == null) {
            throw new ContractException("ok", "missing");
        }
        double[] position = Json.optDoubles(o, "position_m", "position_m", 3);
        if (ok && position == null) {
            throw new ContractException("position_m", "missing in a successful result");
        }
        String reason = Json.optString(o, "reason", "reason");
        if (!ok && reason == null) {
            throw new ContractException("reason", "missing in a refused result");
        }
        Long beaconId = Json.optLong(o, "beacon_id", "beacon_id");
        Boolean gravityUsed = Json.optBoolean(o, "gravity_used", "gravity_used");
        return new LocateResult(ok, position, Json.optRows(o, "rotation_wc", "rotation_wc", 3, 3),
                Json.optDoubles(o, "yaw_pitch_roll_deg", "yaw_pitch_roll_deg", 3),
                beaconId == null ? null : Integer.valueOf(beaconId.intValue()),
                Json.optString(o, "beacon_id_source", "beacon_id_source"),
                Json.optString(o, "orientation_rule", "orientation_rule"),
                Json.optDoubles(o, "center_px", "center_px", 2),
                Json.optDouble(o, "reprojection_error_px", "reprojection_error_px"),
                gravityUsed != null && gravityUsed, Json.optDoubles(o, "position_sigma_m", "position_sigma_m", 3),
                Json.optRows(o, "position_covariance_m2", "position_covariance_m2", 3, 3), reason,
                Json.optString(o, "message", "message"),
                Json.optStrings(o, "warnings", "warnings"));
    }
}
