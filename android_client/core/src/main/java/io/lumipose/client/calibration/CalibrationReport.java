package io.lumipose.client.calibration;

import java.util.ArrayList;
import java.util.Collections;
import java.util.List;

import org.json.JSONObject;

import io.lumipose.client.camera.DeviceProfile;
import io.lumipose.client.json.ContractException;
import io.lumipose.client.json.Json;

/**
 * The contract's {@code CalibrationReport} ({@code lumipose.calibration/1}), the parts the screen
 * shows: whether the set passed, the calibrated profile, the RMS, the coverage and its cells, the
 * advice on what to shoot next, and each photo left out with the reason.
 */
public final class CalibrationReport {
    public static final String SCHEMA = "lumipose.calibration/1";
    public final boolean ok;
    /** The calibrated profile; null unless ok. */
    public final DeviceProfile profile;
    public final Double rmsPx;
    public final double coverage;
    private final int[][] coverageCells;
    public final Double maxTiltDeg;
    public final List<String> advice;
    /** "name: note" of every photo the fit left out. */
    public final List<String> leftOut;
    public final String message;

    private CalibrationReport(boolean ok, DeviceProfile profile, Double rmsPx, double coverage, int[][] coverageCells,
                              Double maxTiltDeg, List<String> advice, List<String> leftOut, String message) {
        this.ok = ok;
        this.profile = profile;
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
        return new CalibrationReport(ok, profile, Json.optDouble(o, "rms_px", "rms_px"), coverage, cells,
                Json.optDouble(o, "max_tilt_deg", "max_tilt_deg"), Json.optStrings(o, "advice", "advice"), leftOut,
                Json.optString(o, "message", "message"));
    }
}
