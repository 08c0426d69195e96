package io.lumipose.client.net;

import java.util.Collections;
import java.util.List;

import org.json.JSONObject;

import io.lumipose.client.json.ContractException;
import io.lumipose.client.json.Json;

/** The contract's result JSON ({@code lumipose.result/1}): a fix, or a refusal with a reason. */
public final class LocateResult {
    public static final String SCHEMA = "lumipose.result/1";

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
    /** Machine-readable refusal, e.g. {@code no_beacon}; null on success. */
    public final String reason;
    public final String message;
    public final List<String> warnings;

    private LocateResult(boolean ok, double[] positionM, double[][] rotationWc, double[] yawPitchRollDeg,
                         Integer beaconId, String beaconIdSource, String orientationRule, double[] centerPx,
                         Double reprojectionErrorPx, boolean gravityUsed, String reason, String message,
                         List<String> warnings) {
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
        this.reason = reason;
        this.message = message;
        this.warnings = Collections.unmodifiableList(warnings);
    }

    /** Camera optical centre in the map frame, m; null when not ok. */
    public double[] positionM() {
        return positionM == null ? null : positionM.clone();
    }

    public double[][] rotationWc() {
        if (rotationWc == null) {
            return null;
        }
        double[][] out = new double[3][];
        for (int i = 0; i < 3; i++) {
            out[i] = rotationWc[i].clone();
        }
        return out;
    }

    /** R_wc = Rz(yaw) Ry(pitch) Rx(roll), degrees; all zero = looking straight up. */
    public double[] yawPitchRollDeg() {
        return yawPitchRollDeg == null ? null : yawPitchRollDeg.clone();
    }

    public double[] centerPx() {
        return centerPx == null ? null : centerPx.clone();
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
                gravityUsed != null && gravityUsed, reason, Json.optString(o, "message", "message"),
                Json.optStrings(o, "warnings", "warnings"));
    }
}
