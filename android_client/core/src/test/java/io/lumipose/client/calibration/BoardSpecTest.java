package io.lumipose.client.calibration;

import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertFalse;
import static org.junit.jupiter.api.Assertions.assertNull;
import static org.junit.jupiter.api.Assertions.assertThrows;
import static org.junit.jupiter.api.Assertions.assertTrue;

import java.nio.charset.StandardCharsets;
import java.nio.file.Files;
import java.nio.file.Path;
import java.util.ArrayList;
import java.util.Arrays;
import java.util.HashSet;
import java.util.List;

import org.json.JSONArray;
import org.json.JSONObject;
import org.junit.jupiter.api.Test;

import io.lumipose.client.json.ContractException;
import io.lumipose.client.testutil.Python;
import io.lumipose.client.testutil.Repo;

/** The boards users already own (issue 29): the app reads every board spec the contract describes. */
class BoardSpecTest {
    private static final String CHARUCO_7X5 = "\"squares_x\": 7, \"squares_y\": 5, \"square_m\": 0.03, "
            + "\"marker_m\": 0.022";

    private static JSONObject boardSchema() throws Exception {
        return new JSONObject(Repo.text("shared_schemas/json/board.schema.json"));
    }

    private static List<String> schemaEnum(String name) throws Exception {
        JSONArray values = boardSchema().getJSONObject("$defs").getJSONObject(name).getJSONArray("enum");
        List<String> out = new ArrayList<String>();
        for (int i = 0; i < values.length(); i++) {
            out.add(values.getString(i));
        }
        return out;
    }

    @Test
    void everyDictionaryAndKindOfTheJsonSchemaIsRead() throws Exception {
        // a 3 x 3 board needs 4 markers: every predefined dictionary holds them
        for (String dictionary : schemaEnum("ArucoDictionary")) {
            BoardSpec b = BoardSpec.fromJson("{\"squares_x\": 3, \"squares_y\": 3, \"square_m\": 0.03, "
                    + "\"marker_m\": 0.02, \"dictionary\": \"" + dictionary + "\"}");
            assertEquals(dictionary, b.dictionary);
        }
        assertEquals(schemaEnum("ArucoDictionary"), BoardSpec.DICTIONARIES, "the same dictionaries, in order");
        assertEquals(schemaEnum("BoardKind"), BoardSpec.KINDS);
        assertEquals(new HashSet<String>(boardSchema().getJSONObject("properties").keySet()),
                new HashSet<String>(BoardSpec.fields()));
    }

    @Test
    void aSpecWithEveryFieldOfTheSchemaRoundTrips() throws Exception {
        JSONObject all = new JSONObject("{\"schema\": \"lumipose.board/1\", \"kind\": \"charuco\", " + CHARUCO_7X5
                + ", \"dictionary\": \"DICT_4X4_1000\", \"legacy\": true, \"first_marker_id\": 100, "
                + "\"inverted\": true}");
        assertEquals(new HashSet<String>(boardSchema().getJSONObject("properties").keySet()), all.keySet(),
                "the spec below has every field the schema has");
        BoardSpec b = BoardSpec.fromJson(all.toString());
        assertEquals(BoardSpec.CHARUCO, b.kind);
        assertEquals(0.022, b.markerM, 0);
        assertTrue(b.legacy);
        assertEquals(100, b.firstMarkerId);
        assertTrue(b.inverted);
        JSONObject written = b.toJson();
        all.remove("kind"); // charuco is the default: written only for a chessboard
        assertTrue(all.similar(written), "written " + written);
        assertEquals(written.toString(), BoardSpec.fromJson(written.toString()).toJson().toString());
    }

    @Test
    void openCvsNineBySixChessboardIsRead() {
        // docs/contract.md: OpenCV's "9 x 6" chessboard (inner corners) is 10 x 7 squares
        BoardSpec b = BoardSpec.fromJson("{\"kind\": \"chessboard\", \"squares_x\": 10, \"squares_y\": 7, "
                + "\"square_m\": 0.025}");
        assertTrue(b.isChessboard());
        assertNull(b.markerM);
        assertEquals(54, b.innerCorners());
        JSONObject written = b.toJson();
        assertEquals(new HashSet<String>(Arrays.asList("schema", "kind", "squares_x", "squares_y", "square_m")),
                written.keySet());
        assertEquals(written.toString(), BoardSpec.chessboard(10, 7, 0.025, false).toJson().toString());
    }

    @Test
    void todaysBoardIsWrittenWithTodaysFields() {
        // as the server's board.json: a server of before this change still takes what the app sends
        JSONObject written = new BoardSpec(7, 5, 0.03, 0.022, null).toJson();
        assertEquals(new HashSet<String>(Arrays.asList("schema", "squares_x", "squares_y", "square_m", "marker_m",
                "dictionary")), written.keySet());
        BoardSpec read = BoardSpec.fromJson(written.toString());
        assertFalse(read.legacy || read.inverted || read.isChessboard());
        assertEquals(0, read.firstMarkerId);
    }

    /** Specs the server accepts or refuses; each refusal's field as the app names it. */
    private static final String[][] SPECS = {
        {"{" + CHARUCO_7X5 + "}", null},
        {"{\"kind\": \"chessboard\", \"squares_x\": 10, \"squares_y\": 7, \"square_m\": 0.025}", null},
        {"{\"kind\": \"chessboard\", \"squares_x\": 10, \"squares_y\": 7, \"square_m\": 0.025, "
            + "\"inverted\": true}", null},
        {"{\"kind\": \"chessboard\", " + CHARUCO_7X5 + "}", "marker_m"},
        {"{\"kind\": \"chessboard\", \"squares_x\": 10, \"squares_y\": 7, \"square_m\": 0.025, \"legacy\": true}",
            "legacy"},
        {"{\"kind\": \"chessboard\", \"squares_x\": 10, \"squares_y\": 7, \"square_m\": 0.025, "
            + "\"first_marker_id\": 3}", "first_marker_id"},
        {"{\"kind\": \"chessboard\", \"squares_x\": 10, \"squares_y\": 7, \"square_m\": 0.025, "
            + "\"dictionary\": \"DICT_5X5_100\"}", "dictionary"},
        {"{\"squares_x\": 7, \"squares_y\": 5, \"square_m\": 0.03}", "marker_m"},
        {"{\"kind\": \"circles\", " + CHARUCO_7X5 + "}", "kind"},
        // 17 markers from id 983 end at 999: the last of DICT_4X4_1000
        {"{" + CHARUCO_7X5 + ", \"dictionary\": \"DICT_4X4_1000\", \"first_marker_id\": 983}", null},
        {"{" + CHARUCO_7X5 + ", \"dictionary\": \"DICT_4X4_1000\", \"first_marker_id\": 984}", "first_marker_id"},
        {"{" + CHARUCO_7X5 + ", \"first_marker_id\": -1}", "first_marker_id"},
        // AprilTag 16h5 holds 30 markers (not in its name): 9 x 7 needs 31, 8 x 7 28
        {"{\"squares_x\": 9, \"squares_y\": 7, \"square_m\": 0.03, \"marker_m\": 0.022, "
            + "\"dictionary\": \"DICT_APRILTAG_16h5\"}", "dictionary"},
        {"{\"squares_x\": 8, \"squares_y\": 7, \"square_m\": 0.03, \"marker_m\": 0.022, "
            + "\"dictionary\": \"DICT_APRILTAG_16h5\"}", null},
        {"{\"squares_x\": 8, \"squares_y\": 7, \"square_m\": 0.03, \"marker_m\": 0.022, "
            + "\"dictionary\": \"DICT_ARUCO_ORIGINAL\", \"legacy\": true}", null},
        {"{" + CHARUCO_7X5 + ", \"mirrored\": true}", "mirrored"},
    };
    /**
     * Refused by the app, taken by the server: pydantic's lax mode reads 1 and "yes" as true; the app wants
     * JSON's true or false, as everywhere it reads JSON (what it writes the server takes either way).
     */
    private static final String[][] STRICTER_THAN_THE_SERVER = {
        {"{" + CHARUCO_7X5 + ", \"legacy\": 1}", "legacy"},
        {"{" + CHARUCO_7X5 + ", \"inverted\": \"yes\"}", "inverted"},
    };

    @Test
    void boardsUsersOwnAreCheckedAsTheAppSays() {
        List<String[]> specs = new ArrayList<String[]>(Arrays.asList(SPECS));
        specs.addAll(Arrays.asList(STRICTER_THAN_THE_SERVER));
        for (String[] s : specs) {
            if (s[1] == null) {
                BoardSpec.fromJson(s[0]);
            } else {
                assertEquals(s[1], assertThrows(ContractException.class, () -> BoardSpec.fromJson(s[0])).field, s[0]);
            }
        }
    }

    @Test
    void theServerAcceptsAndRefusesTheSameSpecs() throws Exception {
        // the server's own BoardSpec (shared_schemas/calibration.py) on the same texts: the app refuses no
        // spec the server takes, and sends none it refuses
        Path dir = Files.createTempDirectory("board-specs");
        JSONArray texts = new JSONArray();
        for (String[] s : SPECS) {
            texts.put(s[0]);
        }
        Files.write(dir.resolve("in.json"), texts.toString().getBytes(StandardCharsets.UTF_8));
        Python.run("calibration/board_specs.py", dir.resolve("in.json").toString(), dir.resolve("out.json").toString());
        JSONArray server = new JSONArray(new String(Files.readAllBytes(dir.resolve("out.json")),
                StandardCharsets.UTF_8));
        for (int i = 0; i < SPECS.length; i++) {
            assertEquals(SPECS[i][1] == null, server.isNull(i), SPECS[i][0] + ": the server says " + server.get(i));
        }
    }
}
