package io.lumipose.client.net;

import java.util.Collections;
import java.util.Iterator;
import java.util.LinkedHashMap;
import java.util.List;
import java.util.Map;

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
    /** Where the beacon ID came from: {@code vlc}, {@code track}, {@code single_beacon_map}, ... */
    public final String beaconIdSource;
    public final String orientationRule;
    private final double[][] cornersPx;
    private final double[] centerPx;
    public final Double reprojectionErrorPx;
    /** Reprojection error of the best pose over the alternative's; null where there is no alternative. */
    public final Double ambiguityRatio;
    public final boolean gravityUsed;
    private final double[] positionSigmaM;
    private final double[][] positionCovarianceM2;
    /** Machine-readable refusal, e.g. {@code no_beacon}; null on success. */
    public final String reason;
    public final String message;
    public final List<String> warnings;
    private final Map<String, Double> timingMs;
    private final VlcReading vlc;
    private final Integer beaconsInView;
    private final Track track;
    /** The object this result was read from, as text: what {@link #toJson} gives back. */
    private final String source;

    /** A device's motion-filtered track at this frame (the contract's {@code TrackState}); the fix is positionM. */
    public static final class Track {
        private final double[] filteredPositionM;
        private final double[] velocityMps;
        /** The raw fix was rejected by the filter's gate. */
        public final boolean outlier;
        /** The beacon ID came from the track, not from this frame. */
        public final boolean beaconIdCarried;

        private Track(JSONObject o) {
            filteredPositionM = requireDoubles(o, "filtered_position_m", "track.filtered_position_m");
            velocityMps = requireDoubles(o, "velocity_mps", "track.velocity_mps");
            outlier = requireBoolean(o, "outlier", "track.outlier");
            Boolean carried = Json.optBoolean(o, "beacon_id_carried", "track.beacon_id_carried");
            beaconIdCarried = carried != null && carried;
        }

        /** Filtered camera position in the map frame, m. */
        public double[] filteredPositionM() {
            return filteredPositionM.clone();
        }

        public double[] velocityMps() {
            return velocityMps.clone();
        }
    }

    /** The beacon ID read from rolling-shutter stripes (the contract's {@code VlcReading}, docs/vlc.md). */
    public static final class VlcReading {
        /** Best ID; null when no stripes were read. */
        public final Integer beaconId;
        /** Posterior probability of {@link #beaconId} among the candidate IDs. */
        public final double confidence;
        /** The confidence reached the decoder's threshold: only then is the ID used. */
        public final boolean confident;
        /** ID frames combined, and the message chips they covered (a message is 21). */
        public final int frames;
        public final double chipsSeen;
        /** IDs considered (the map's, or all 256). */
        public final int candidates;

        private VlcReading(JSONObject o) {
            Long id = Json.optLong(o, "beacon_id", "vlc.beacon_id");
            beaconId = id == null ? null : Integer.valueOf(id.intValue());
            confidence = Json.requireDouble(o, "confidence", "vlc.confidence");
            confident = requireBoolean(o, "confident", "vlc.confident");
            frames = Json.requireInt(o, "frames", "vlc.frames");
            chipsSeen = Json.requireDouble(o, "chips_seen", "vlc.chips_seen");
            candidates = Json.requireInt(o, "candidates", "vlc.candidates");
        }
    }

    private LocateResult(JSONObject o, boolean ok, double[] positionM, String reason) {
        this.source = o.toString();
        this.ok = ok;
        this.positionM = positionM;
        this.reason = reason;
        rotationWc = Json.optRows(o, "rotation_wc", "rotation_wc", 3, 3);
        yawPitchRollDeg = Json.optDoubles(o, "yaw_pitch_roll_deg", "yaw_pitch_roll_deg", 3);
        Long id = Json.optLong(o, "beacon_id", "beacon_id");
        beaconId = id == null ? null : Integer.valueOf(id.intValue());
        beaconIdSource = Json.optString(o, "beacon_id_source", "beacon_id_source");
        orientationRule = Json.optString(o, "orientation_rule", "orientation_rule");
        cornersPx = Json.optRows(o, "corners_px", "corners_px", 4, 2);
        centerPx = Json.optDoubles(o, "center_px", "center_px", 2);
        reprojectionErrorPx = Json.optDouble(o, "reprojection_error_px", "reprojection_error_px");
        ambiguityRatio = Json.optDouble(o, "ambiguity_ratio", "ambiguity_ratio");
        Boolean gravity = Json.optBoolean(o, "gravity_used", "gravity_used");
        gravityUsed = gravity != null && gravity;
        positionSigmaM = Json.optDoubles(o, "position_sigma_m", "position_sigma_m", 3);
        positionCovarianceM2 = Json.optRows(o, "position_covariance_m2", "position_covariance_m2", 3, 3);
        message = Json.optString(o, "message", "message");
        warnings = Collections.unmodifiableList(Json.optStrings(o, "warnings", "warnings"));
        timingMs = Collections.unmodifiableMap(timings(Json.optObject(o, "timing_ms", "timing_ms")));
        JSONObject reading = Json.optObject(o, "vlc", "vlc");
        vlc = reading == null ? null : new VlcReading(reading);
        Long inView = Json.optLong(o, "beacons_in_view", "beacons_in_view");
        beaconsInView = inView == null ? null : Integer.valueOf(inView.intValue());
        JSONObject filtered = Json.optObject(o, "track", "track");
        track = filtered == null ? null : new Track(filtered);
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
     * The panel's 4 corners in the beacon model's corner order, in the frame's pixels (the window's, for a
     * cropped frame); null without corners (a refusal, a circle, a panel cut by the border).
     */
    public double[][] cornersPx() {
        return copy(cornersPx);
    }

    /** Time of each pipeline stage and the {@code total}, ms (read-only); empty when not given. */
    public Map<String, Double> timingMs() {
        return timingMs;
    }

    /** The ID read by VLC for this fix; null when none was read. */
    public VlcReading vlc() {
        return vlc;
    }

    /** Beacon-shaped blobs the server saw in the frame; null when it does not say. */
    public Integer beaconsInView() {
        return beaconsInView;
    }

    /** The device's filtered track (when the frame came with a device id); null otherwise. */
    public Track track() {
        return track;
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

    /** The result as the server sent it (a copy: every field, known or not); {@link #fromJson} reads it back. */
    public JSONObject toJson() {
        return Json.parseObject(source, "result");
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
        return new LocateResult(o, ok, position, reason);
    }

    private static Map<String, Double> timings(JSONObject o) {
        Map<String, Double> out = new LinkedHashMap<String, Double>();
        if (o != null) {
            for (Iterator<String> keys = o.keys(); keys.hasNext(); ) {
                String stage = keys.next();
                out.put(stage, Json.requireDouble(o, stage, "timing_ms." + stage));
            }
        }
        return out;
    }

    private static double[] requireDoubles(JSONObject o, String key, String path) {
        double[] values = Json.optDoubles(o, key, path, 3);
        if (values == null) {
            throw new ContractException(path, "missing");
        }
        return values;
    }

    private static boolean requireBoolean(JSONObject o, String key, String path) {
        Boolean value = Json.optBoolean(o, key, path);
        if (value == null) {
            throw new ContractException(path, "missing");
        }
        return value;
    }
}
