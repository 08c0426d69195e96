package io.lumipose.client.calibration;

import java.util.ArrayList;
import java.util.Collections;
import java.util.List;

import org.json.JSONObject;

import io.lumipose.client.camera.DeviceProfile;
import io.lumipose.client.contract.ContractRanges;
import io.lumipose.client.json.ContractException;
import io.lumipose.client.json.Json;

/**
 * The contract's {@code CalibrationReport} ({@code lumipose.calibration/1}), the parts the screen
 * shows: whether the set passed, the calibrated profile, what the fit gave (also for a refused set,
 * then not trusted), the RMS, the coverage and its cells, the advice on what to shoot next, and each
 * photo left out with the reason.
 */
public final class CalibrationReport {
    public static final String SCHEMA = "lumipose.calibration/1";
    public final boolean ok;
    /** The calibrated profile; null unless ok. */
    public final DeviceProfile profile;
    /** What the fit gave, trusted or not; null when nothing could be fitted. */
    public final Fitted fitted;
    public final Double rmsPx;
    public final double coverage;
    private final int[][] coverageCells;
    public final Double maxTiltDeg;
    public final List<String> advice;
    /** "name: note" of every photo the fit left out. */
    public final List<String> leftOut;
    public final String message;

    /**
     * The contract's {@code FittedCamera}: the fitted pinhole and distortion at the photos' size. When not
     * {@code trusted} (the set was refused) the values are for a look, never for positioning.
     */
    public static final class Fitted {
        public final boolean trusted;
        public final int width;
        public final int height;
        public final double fx;
        public final double fy;
        public final double cx;
        public final double cy;
        private final double[] distortion;

        Fitted(JSONObject o, String path) {
            Boolean t = Json.optBoolean(o, "trusted", path + "trusted");
            if (t == null) {
                throw new ContractException(path + "trusted", "missing");
            }
            trusted = t;
            width = Json.requireInt(o, "width", path + "width");
            height = Json.requireInt(o, "height", path + "height");
            ContractRanges.SIDE_PX.check(path + "width", width);
            ContractRanges.SIDE_PX.check(path + "height", height);
            fx = Json.requireDouble(o, "fx", path + "fx");
            fy = Json.requireDouble(o, "fy", path + "fy");
            cx = Json.requireDouble(o, "cx", path + "cx");
            cy = Json.requireDouble(o, "cy", path + "cy");
            distortion = Json.optDoubles(o, "distortion", path + "distortion", 5);
            if (distortion == null) {
                throw new ContractException(path + "distortion", "missing");
            }
        }

        /** k1, k2, p1, p2, k3 (OpenCV's). */
        public double[] distortion() {
            return distortion.clone();
        }
    }

    private CalibrationReport(boolean ok, DeviceProfile profile, Fitted fitted, Double rmsPx, double coverage,
                              int[][] coverageCells, Double maxTiltDeg, List<String> advice, List<String> leftOut,
                              String message) {
        this.ok = ok;
        this.profile = profile;
        this.fitted = fitted;
        this.rmsPx = rmsPx;
        this.coverage = coverage;
        this.coverageCells = coverageCells;
        this.maxTiltDeg = maxTiltDeg;
        this.advice = Collections.unmodifiableList(advice);
        this.leftOut = Collections.unmodifiableList(leftOut);
        this.message = message;
    }

    /** Corners per cell as the server counted them, rows top to bottom; empty when not given. */
    public int[][] coverageCells() {
        int[][] out = new int[coverageCells.length][];
        for (int r = 0; r < out.length; r++) {
            out[r] = coverageCells[r].clone();
        }
        return out;
    }

    public static CalibrationReport fromJson(String text) {
        JSONObject o = Json.parseObject(text, "calibration report");
        Json.checkSchema(o, SCHEMA);
        Boolean ok = Json.optBoolean(o, "ok", "ok");
        if (ok == null) {
            throw new ContractException("ok", "missing");
        }
        JSONObject p = Json.optObject(o, "profile", "profile");
        DeviceProfile profile = p == null ? null : DeviceProfile.fromJson(p, "profile.");
        if (ok && profile == null) {
            throw new ContractException("profile", "an ok report must carry the calibrated profile");
        }
        JSONObject f = Json.optObject(o, "fitted", "fitted");
        Fitted fitted = f == null ? null : new Fitted(f, "fitted.");
        if (fitted != null && fitted.trusted != ok) {
            throw new ContractException("fitted.trusted", "must be the report's ok (" + ok + ")");
        }
        Double coverage = Json.optDouble(o, "coverage", "coverage");
        if (coverage == null || !(coverage >= 0 && coverage <= 1)) {
            throw new ContractException("coverage", "must be within [0, 1], got " + coverage);
        }
        double[][] rows = Json.optRows(o, "coverage_cells", "coverage_cells", -1, -1);
        int[][] cells = new int[rows == null ? 0 : rows.length][];
        for (int r = 0; r < cells.length; r++) {
            if (rows[r].length != rows[0].length) {
                throw new ContractException("coverage_cells[" + r + "]", "rows must be of one length");
            }
            cells[r] = new int[rows[r].length];
            for (int c = 0; c < cells[r].length; c++) {
                cells[r][c] = (int) rows[r][c];
            }
        }
        List<String> leftOut = new ArrayList<String>();
        List<JSONObject> views = Json.optObjects(o, "views", "views");
        for (int i = 0; i < views.size(); i++) {
            String note = Json.optString(views.get(i), "note", "views[" + i + "].note");
            if (note != null) {
                leftOut.add(Json.optString(views.get(i), "name", "views[" + i + "].name") + ": " + note);
            }
        }
        return new CalibrationReport(ok, profile, fitted, Json.optDouble(o, "rms_px", "rms_px"), coverage, cells,
                Json.optDouble(o, "max_tilt_deg", "max_tilt_deg"), Json.optStrings(o, "advice", "advice"), leftOut,
                Json.optString(o, "message", "message"));
    }
}
