package io.lumipose.client.calibration;

import java.util.Arrays;
import java.util.List;

import org.json.JSONObject;

import io.lumipose.client.json.ContractException;
import io.lumipose.client.json.Json;

/**
 * The contract's {@code BoardSpec} ({@code lumipose.board/1}): the ChArUco board the user printed
 * ({@code lumipose calibrate board} writes it as board.json beside the print). Checked as the server
 * checks it, so a wrong spec is named on the phone before any photo goes up.
 */
public final class BoardSpec {
    public static final String SCHEMA = "lumipose.board/1";
    public static final String DEFAULT_DICTIONARY = "DICT_5X5_100";
    /** OpenCV's predefined dictionaries the contract accepts. */
    public static final List<String> DICTIONARIES = Arrays.asList("DICT_4X4_50", "DICT_4X4_100", "DICT_4X4_250",
            "DICT_4X4_1000", "DICT_5X5_100", "DICT_5X5_250", "DICT_5X5_1000", "DICT_6X6_250", "DICT_6X6_1000");
    private static final int MAX_SQUARES = 64;
    private static final double MIN_SQUARE_M = 1e-3;
    private static final double MAX_SQUARE_M = 1.0;

    public final int squaresX;
    public final int squaresY;
    public final double squareM;
    public final double markerM;
    public final String dictionary;

    public BoardSpec(int squaresX, int squaresY, double squareM, double markerM, String dictionary) {
        checkSquares("squares_x", squaresX);
        checkSquares("squares_y", squaresY);
        if (!(squareM >= MIN_SQUARE_M && squareM <= MAX_SQUARE_M)) {
            throw new ContractException("square_m", "must be within [0.001, 1] m, got " + squareM);
        }
        if (!(markerM >= MIN_SQUARE_M / 2 && markerM <= MAX_SQUARE_M)) {
            throw new ContractException("marker_m", "must be within [0.0005, 1] m, got " + markerM);
        }
        if (markerM >= squareM) {
            throw new ContractException("marker_m", "must be smaller than square_m (" + squareM + "), got " + markerM);
        }
        String dict = dictionary == null ? DEFAULT_DICTIONARY : dictionary;
        if (!DICTIONARIES.contains(dict)) {
            throw new ContractException("dictionary", "must be one of " + DICTIONARIES + ", got '" + dict + "'");
        }
        int markers = squaresX * squaresY / 2;
        int size = Integer.parseInt(dict.substring(dict.lastIndexOf('_') + 1));
        if (markers > size) {
            throw new ContractException("dictionary", "a " + squaresX + " x " + squaresY + " board needs " + markers
                    + " markers; " + dict + " has " + size);
        }
        this.squaresX = squaresX;
        this.squaresY = squaresY;
        this.squareM = squareM;
        this.markerM = markerM;
        this.dictionary = dict;
    }

    private static void checkSquares(String field, int n) {
        if (n < 3 || n > MAX_SQUARES) {
            throw new ContractException(field, "must be within [3, 64], got " + n);
        }
    }

    /** ChArUco corners (where four squares meet). */
    public int innerCorners() {
        return (squaresX - 1) * (squaresY - 1);
    }

    public JSONObject toJson() {
        JSONObject o = new JSONObject();
        Json.put(o, "schema", SCHEMA);
        Json.put(o, "squares_x", squaresX);
        Json.put(o, "squares_y", squaresY);
        Json.put(o, "square_m", squareM);
        Json.put(o, "marker_m", markerM);
        Json.put(o, "dictionary", dictionary);
        return o;
    }

    /** A board.json as {@code lumipose calibrate board} writes it; unknown fields are refused, as the server does. */
    public static BoardSpec fromJson(String text) {
        JSONObject o = Json.parseObject(text, "board");
        Json.checkSchema(o, SCHEMA);
        JSONObject unknown = Json.extras(o, new java.util.HashSet<String>(Arrays.asList("schema", "squares_x",
                "squares_y", "square_m", "marker_m", "dictionary")));
        if (unknown.length() > 0) {
            throw new ContractException(unknown.keys().next(), "not a field of a board spec");
        }
        return new BoardSpec(Json.requireInt(o, "squares_x", "squares_x"), Json.requireInt(o, "squares_y", "squares_y"),
                Json.requireDouble(o, "square_m", "square_m"), Json.requireDouble(o, "marker_m", "marker_m"),
                Json.optString(o, "dictionary", "dictionary"));
    }
}
