package io.lumipose.client.calibration;

import java.util.HashSet;
import java.util.List;
import java.util.Set;

import org.json.JSONArray;
import org.json.JSONObject;

import io.lumipose.client.contract.ContractRanges;
import io.lumipose.client.json.ContractException;
import io.lumipose.client.json.Json;

/**
 * The contract's {@code BoardView}: the board's corners found on one photo (corner ids and
 * their sub-pixel image points, OpenCV pixel coordinates), as {@code POST /v1/calibrations/views}
 * returns it, with whether the board was found {@code inverted} and the photo {@code mirrored} (a
 * front camera's: its corners are then those of the photo flipped left-right back). The app keeps
 * these small records and sends them back in the calibration request, never the photos again; the
 * two flags go back too, so the report can say how the board was found.
 */
public final class BoardView {
    /** Corner ids are below squares_x x squares_y of the largest board (64 x 64). */
    private static final int MAX_CORNER_ID = 64 * 64;
    public final String name;
    public final int width;
    public final int height;
    private final int[] cornerIds;
    private final double[][] cornersPx;
    /** The board was found inverted (white markers on black). */
    public final boolean inverted;
    /** The photo was mirrored: the corners are those of the un-mirrored photo. */
    public final boolean mirrored;

    public BoardView(String name, int width, int height, int[] cornerIds, double[][] cornersPx) {
        this(name, width, height, cornerIds, cornersPx, false, false);
    }

    public BoardView(String name, int width, int height, int[] cornerIds, double[][] cornersPx, boolean inverted,
                     boolean mirrored) {
        if (name == null || name.length() > 256) {
            throw new ContractException("name", "must be a string of at most 256 characters");
        }
        ContractRanges.SIDE_PX.check("width", width);
        ContractRanges.SIDE_PX.check("height", height);
        if (cornerIds.length != cornersPx.length) {
            throw new ContractException("corners_px", cornerIds.length + " corner_ids but " + cornersPx.length
                    + " corners_px");
        }
        Set<Integer> seen = new HashSet<Integer>();
        for (int i = 0; i < cornerIds.length; i++) {
            if (cornerIds[i] < 0 || cornerIds[i] >= MAX_CORNER_ID || !seen.add(cornerIds[i])) {
                throw new ContractException("corner_ids[" + i + "]", "must be unique and within [0, 4096), got "
                        + cornerIds[i]);
            }
            if (cornersPx[i].length != 2) {
                throw new ContractException("corners_px[" + i + "]", "must be [x, y]");
            }
        }
        this.name = name;
        this.width = width;
        this.height = height;
        this.cornerIds = cornerIds.clone();
        this.cornersPx = new double[cornersPx.length][];
        for (int i = 0; i < cornersPx.length; i++) {
            this.cornersPx[i] = cornersPx[i].clone();
        }
        this.inverted = inverted;
        this.mirrored = mirrored;
    }

    public int corners() {
        return cornerIds.length;
    }

    public int cornerId(int i) {
        return cornerIds[i];
    }

    /** The i-th corner's [x, y], px. */
    public double[] cornerPx(int i) {
        return cornersPx[i].clone();
    }

    /** How the server found the board when not as printed, as the photo's line says it ("" when as printed). */
    public String foundAs() {
        if (!inverted && !mirrored) {
            return "";
        }
        return " (" + (inverted ? "board found inverted" : "") + (inverted && mirrored ? ", " : "")
                + (mirrored ? "photo mirrored: un-mirrored" : "") + ")";
    }

    public JSONObject toJson() {
        JSONObject o = new JSONObject();
        Json.put(o, "name", name);
        Json.put(o, "width", width);
        Json.put(o, "height", height);
        JSONArray ids = new JSONArray();
        for (int id : cornerIds) {
            ids.put(id);
        }
        Json.put(o, "corner_ids", ids);
        Json.put(o, "corners_px", Json.matrix(cornersPx));
        // only when said: the server of before this field refuses fields it does not know
        if (inverted) {
            Json.put(o, "inverted", true);
        }
        if (mirrored) {
            Json.put(o, "mirrored", true);
        }
        return o;
    }

    public static BoardView fromJson(String text) {
        JSONObject o = Json.parseObject(text, "board view");
        double[] ids = Json.optDoubles(o, "corner_ids", "corner_ids", -1);
        double[][] corners = Json.optRows(o, "corners_px", "corners_px", -1, 2);
        if (ids == null || corners == null) {
            throw new ContractException(ids == null ? "corner_ids" : "corners_px", "missing");
        }
        int[] intIds = new int[ids.length];
        for (int i = 0; i < ids.length; i++) {
            if (ids[i] != Math.rint(ids[i])) {
                throw new ContractException("corner_ids[" + i + "]", "must be an integer, got " + ids[i]);
            }
            intIds[i] = (int) ids[i];
        }
        String name = Json.optString(o, "name", "name");
        Boolean inverted = Json.optBoolean(o, "inverted", "inverted");
        Boolean mirrored = Json.optBoolean(o, "mirrored", "mirrored");
        return new BoardView(name == null ? "" : name, Json.requireInt(o, "width", "width"),
                Json.requireInt(o, "height", "height"), intIds, corners, inverted != null && inverted,
                mirrored != null && mirrored);
    }

    static JSONArray toJson(List<BoardView> views) {
        JSONArray a = new JSONArray();
        for (BoardView v : views) {
            a.put(v.toJson());
        }
        return a;
    }
}
