package io.lumipose.client.calibration;

import java.util.ArrayList;
import java.util.Arrays;
import java.util.Collections;
import java.util.HashSet;
import java.util.LinkedHashMap;
import java.util.List;
import java.util.Map;

import org.json.JSONObject;

import io.lumipose.client.json.ContractException;
import io.lumipose.client.json.Json;

/**
 * The contract's {@code BoardSpec} ({@code lumipose.board/1}): the calibration board the user printed or
 * already owns ({@code lumipose calibrate board} writes it as board.json beside the print). A ChArUco board
 * ({@link #CHARUCO}, the default: any of OpenCV's predefined dictionaries, OpenCV's layout before 4.6 with
 * {@code legacy}, markers from {@code first_marker_id}) or a plain chessboard ({@link #CHESSBOARD}: no
 * markers), possibly printed {@code inverted}. Checked as the server checks it, so a wrong spec is named on
 * the phone before any photo goes up.
 */
public final class BoardSpec {
    public static final String SCHEMA = "lumipose.board/1";
    public static final String CHARUCO = "charuco";
    public static final String CHESSBOARD = "chessboard";
    /** The contract's {@code BoardKind} values. */
    public static final List<String> KINDS = Collections.unmodifiableList(Arrays.asList(CHARUCO, CHESSBOARD));
    public static final String DEFAULT_DICTIONARY = "DICT_5X5_100";
    /** Markers in each of OpenCV's predefined dictionaries the contract accepts (not all sizes are in the name). */
    private static final Map<String, Integer> DICTIONARY_SIZES = new LinkedHashMap<String, Integer>();

    static {
        for (String bits : new String[] {"4X4", "5X5", "6X6", "7X7"}) {
            for (int size : new int[] {50, 100, 250, 1000}) {
                DICTIONARY_SIZES.put("DICT_" + bits + "_" + size, size);
            }
        }
        DICTIONARY_SIZES.put("DICT_ARUCO_ORIGINAL", 1024);
        DICTIONARY_SIZES.put("DICT_APRILTAG_16h5", 30);
        DICTIONARY_SIZES.put("DICT_APRILTAG_25h9", 35);
        DICTIONARY_SIZES.put("DICT_APRILTAG_36h10", 2320);
        DICTIONARY_SIZES.put("DICT_APRILTAG_36h11", 587);
        DICTIONARY_SIZES.put("DICT_ARUCO_MIP_36h12", 250);
    }

    /** OpenCV's predefined dictionaries the contract accepts (every one of OpenCV 4.6 and later). */
    public static final List<String> DICTIONARIES = Collections.unmodifiableList(
            new ArrayList<String>(DICTIONARY_SIZES.keySet()));
    private static final List<String> FIELDS = Collections.unmodifiableList(Arrays.asList("schema", "kind",
            "squares_x", "squares_y", "square_m", "marker_m", "dictionary", "legacy", "first_marker_id", "inverted"));
    private static final int MAX_SQUARES = 64;
    private static final double MIN_SQUARE_M = 1e-3;
    private static final double MAX_SQUARE_M = 1.0;

    public final String kind;
    public final int squaresX;
    public final int squaresY;
    public final double squareM;
    /** Side of one marker, m; null on a chessboard. */
    public final Double markerM;
    /** The markers' dictionary (on a chessboard the default, unused, and neither given nor written). */
    public final String dictionary;
    /** OpenCV's ChArUco layout before 4.6 (an even number of rows starts with a white square). */
    public final boolean legacy;
    /** The top-left marker's id. */
    public final int firstMarkerId;
    /** Printed inverted: white markers on black squares. */
    public final boolean inverted;

    /** Today's ChArUco board (OpenCV 4.6's layout, markers from id 0, printed black on white). */
    public BoardSpec(int squaresX, int squaresY, double squareM, double markerM, String dictionary) {
        this(CHARUCO, squaresX, squaresY, squareM, markerM, dictionary, false, 0, false);
    }

    public BoardSpec(String kind, int squaresX, int squaresY, double squareM, Double markerM, String dictionary,
                     boolean legacy, int firstMarkerId, boolean inverted) {
        String k = kind == null ? CHARUCO : kind;
        if (!KINDS.contains(k)) {
            throw new ContractException("kind", "must be one of " + KINDS + ", got '" + k + "'");
        }
        checkSquares("squares_x", squaresX);
        checkSquares("squares_y", squaresY);
        if (!(squareM >= MIN_SQUARE_M && squareM <= MAX_SQUARE_M)) {
            throw new ContractException("square_m", "must be within [0.001, 1] m, got " + squareM);
        }
        if (markerM != null && !(markerM >= MIN_SQUARE_M / 2 && markerM <= MAX_SQUARE_M)) {
            throw new ContractException("marker_m", "must be within [0.0005, 1] m, got " + markerM);
        }
        if (firstMarkerId < 0) {
            throw new ContractException("first_marker_id", "must be at least 0, got " + firstMarkerId);
        }
        String dict = dictionary == null ? DEFAULT_DICTIONARY : dictionary;
        if (!DICTIONARY_SIZES.containsKey(dict)) {
            throw new ContractException("dictionary", "must be one of " + DICTIONARIES + ", got '" + dict + "'");
        }
        if (CHESSBOARD.equals(k)) {
            String marked = markerM != null ? "marker_m" : legacy ? "legacy" : firstMarkerId != 0 ? "first_marker_id"
                    : dictionary != null ? "dictionary" : null;
            if (marked != null) {
                throw new ContractException(marked, "a chessboard has no markers: marker_m, legacy, "
                        + "first_marker_id and dictionary are ChArUco's");
            }
        } else {
            if (markerM == null) {
                throw new ContractException("marker_m", "a ChArUco board needs marker_m (the side of one marker)");
            }
            if (markerM >= squareM) {
                throw new ContractException("marker_m", "must be smaller than square_m (" + squareM + "), got "
                        + markerM);
            }
            int markers = squaresX * squaresY / 2;
            int size = DICTIONARY_SIZES.get(dict);
            // a long: first_marker_id has no upper bound in the contract
            if ((long) firstMarkerId + markers > size) {
                throw new ContractException(firstMarkerId != 0 ? "first_marker_id" : "dictionary", "a " + squaresX
                        + " x " + squaresY + " board needs " + markers + " markers"
                        + (firstMarkerId != 0 ? " from id " + firstMarkerId : "") + "; " + dict + " has " + size
                        + " (ids 0 to " + (size - 1) + ")");
            }
        }
        this.kind = k;
        this.squaresX = squaresX;
        this.squaresY = squaresY;
        this.squareM = squareM;
        this.markerM = markerM;
        this.dictionary = dict;
        this.legacy = legacy;
        this.firstMarkerId = firstMarkerId;
        this.inverted = inverted;
    }

    /** A plain chessboard of {@code squaresX} x {@code squaresY} squares (OpenCV's "9 x 6" pattern is 10 x 7). */
    public static BoardSpec chessboard(int squaresX, int squaresY, double squareM, boolean inverted) {
        return new BoardSpec(CHESSBOARD, squaresX, squaresY, squareM, null, null, false, 0, inverted);
    }

    private static void checkSquares(String field, int n) {
        if (n < 3 || n > MAX_SQUARES) {
            throw new ContractException(field, "must be within [3, 64], got " + n);
        }
    }

    /** Markers in {@code dictionary}; null for a name the contract does not have. */
    public static Integer dictionarySize(String dictionary) {
        return DICTIONARY_SIZES.get(dictionary);
    }

    /** Corners where four squares meet (a ChArUco board's corners, a chessboard's inner corners). */
    public int innerCorners() {
        return (squaresX - 1) * (squaresY - 1);
    }

    public boolean isChessboard() {
        return CHESSBOARD.equals(kind);
    }

    /**
     * The spec as the server writes board.json: the fields added for other boards (issue 29) only when not at
     * their default, so today's board reads as before on a server of before.
     */
    public JSONObject toJson() {
        JSONObject o = new JSONObject();
        Json.put(o, "schema", SCHEMA);
        if (!CHARUCO.equals(kind)) {
            Json.put(o, "kind", kind);
        }
        Json.put(o, "squares_x", squaresX);
        Json.put(o, "squares_y", squaresY);
        Json.put(o, "square_m", squareM);
        if (markerM != null) {
            Json.put(o, "marker_m", markerM);
        }
        if (!isChessboard()) {
            Json.put(o, "dictionary", dictionary);
        }
        if (legacy) {
            Json.put(o, "legacy", true);
        }
        if (firstMarkerId != 0) {
            Json.put(o, "first_marker_id", firstMarkerId);
        }
        if (inverted) {
            Json.put(o, "inverted", true);
        }
        return o;
    }

    /** A board.json as {@code lumipose calibrate board} writes it; unknown fields are refused, as the server does. */
    public static BoardSpec fromJson(String text) {
        JSONObject o = Json.parseObject(text, "board");
        Json.checkSchema(o, SCHEMA);
        JSONObject unknown = Json.extras(o, new HashSet<String>(FIELDS));
        if (unknown.length() > 0) {
            throw new ContractException(unknown.keys().next(), "not a field of a board spec");
        }
        Boolean legacy = Json.optBoolean(o, "legacy", "legacy");
        Boolean inverted = Json.optBoolean(o, "inverted", "inverted");
        return new BoardSpec(Json.optString(o, "kind", "kind"), Json.requireInt(o, "squares_x", "squares_x"),
                Json.requireInt(o, "squares_y", "squares_y"), Json.requireDouble(o, "square_m", "square_m"),
                Json.optDouble(o, "marker_m", "marker_m"), Json.optString(o, "dictionary", "dictionary"),
                legacy != null && legacy, Json.isPresent(o, "first_marker_id")
                        ? Json.requireInt(o, "first_marker_id", "first_marker_id") : 0,
                inverted != null && inverted);
    }

    /** The fields a board spec has, in the contract's order. */
    public static List<String> fields() {
        return FIELDS;
    }
}
