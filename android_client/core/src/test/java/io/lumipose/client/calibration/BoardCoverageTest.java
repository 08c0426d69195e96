package io.lumipose.client.calibration;

import static org.junit.jupiter.api.Assertions.assertArrayEquals;
import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertThrows;
import static org.junit.jupiter.api.Assertions.assertTrue;

import java.util.Arrays;

import org.junit.jupiter.api.Test;

class BoardCoverageTest {
    private static BoardView view(String name, int width, int height, double[]... corners) {
        int[] ids = new int[corners.length];
        for (int i = 0; i < ids.length; i++) {
            ids[i] = i;
        }
        return new BoardView(name, width, height, ids, corners);
    }

    @Test
    void theDefaultGridIsTheServersSixByFour() {
        BoardCoverage landscape = BoardCoverage.forImage(1920, 1080);
        assertEquals(6, landscape.columns);
        assertEquals(4, landscape.rows);
        BoardCoverage portrait = BoardCoverage.forImage(3000, 4000);
        assertEquals(6, portrait.rows);
        assertEquals(4, portrait.columns);
    }

    /** Each corner counts in the cell it falls in, rows top to bottom; edges and beyond count at the edge. */
    @Test
    void cornersCountInTheirCells() {
        BoardCoverage c = new BoardCoverage(800, 600, 3, 4);
        assertEquals(0.0, c.coverage(), 0.0);
        c.add(view("a", 800, 600, new double[] {10, 10}, new double[] {199.4, 10}, new double[] {199.6, 10},
                new double[] {790, 590}, new double[] {-0.5, 1000}, new double[] {401, 299}));
        assertArrayEquals(new int[] {2, 1, 0, 0}, c.counts()[0]);
        assertArrayEquals(new int[] {0, 0, 1, 0}, c.counts()[1]);
        assertArrayEquals(new int[] {1, 0, 0, 1}, c.counts()[2]);
        assertEquals(0.0, c.coverage(), 0.0, "no cell holds 3 corners yet");
        c.add(view("b", 800, 600, new double[] {10, 10}, new double[] {790, 599}, new double[] {795, 580}));
        assertEquals(3, c.count(0, 0));
        assertTrue(c.covered(0, 0));
        assertTrue(c.covered(2, 3));
        assertEquals(2.0 / 12, c.coverage(), 1e-12);
        BoardCoverage again = BoardCoverage.of(Arrays.asList(view("a", 800, 600, new double[] {10, 10},
                new double[] {11, 10}, new double[] {12, 10})), 800, 600, 3, 4);
        assertEquals(1.0 / 12, again.coverage(), 1e-12);
    }

    @Test
    void aPhotoOfAnotherSizeIsRefused() {
        BoardCoverage c = new BoardCoverage(800, 600, 3, 4);
        IllegalArgumentException e = assertThrows(IllegalArgumentException.class,
                () -> c.add(view("small", 640, 480, new double[] {1, 1})));
        assertEquals("photo 'small' is 640x480, the others 800x600", e.getMessage());
        assertThrows(IllegalArgumentException.class, () -> new BoardCoverage(800, 600, 0, 4));
    }

    @Test
    void boardSpecsAreCheckedAsTheServerChecksThem() {
        BoardSpec ok = BoardSpec.fromJson(
                "{\"squares_x\": 7, \"squares_y\": 5, \"square_m\": 0.03, \"marker_m\": 0.022}");
        assertEquals("DICT_5X5_100", ok.dictionary);
        assertEquals(24, ok.innerCorners());
        assertEquals(ok.toJson().toString(), BoardSpec.fromJson(ok.toJson().toString()).toJson().toString());
        String[][] bad = {
            {"{\"squares_x\": 2, \"squares_y\": 5, \"square_m\": 0.03, \"marker_m\": 0.022}", "squares_x"},
            {"{\"squares_x\": 7, \"squares_y\": 5, \"square_m\": 0.03, \"marker_m\": 0.03}", "marker_m"},
            {"{\"squares_x\": 7, \"squares_y\": 5, \"square_m\": 3, \"marker_m\": 0.022}", "square_m"},
            {"{\"squares_x\": 20, \"squares_y\": 20, \"square_m\": 0.03, \"marker_m\": 0.022, "
                + "\"dictionary\": \"DICT_4X4_50\"}", "dictionary"},
            {"{\"squares_x\": 7, \"squares_y\": 5, \"square_m\": 0.03, \"marker_m\": 0.022, \"dictionary\": \"X\"}",
                "dictionary"},
            {"{\"squares_x\": 7, \"squares_y\": 5, \"square_m\": 0.03, \"marker_m\": 0.022, \"size\": 1}", "size"},
            {"{\"squares_y\": 5, \"square_m\": 0.03, \"marker_m\": 0.022}", "squares_x"},
            {"{\"schema\": \"lumipose.board/2\", \"squares_x\": 7, \"squares_y\": 5, \"square_m\": 0.03, "
                + "\"marker_m\": 0.022}", "schema"},
        };
        for (String[] b : bad) {
            assertEquals(b[1], assertThrows(io.lumipose.client.json.ContractException.class,
                    () -> BoardSpec.fromJson(b[0])).field, b[0]);
        }
    }
}
