package io.lumipose.client.calibration;

import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertFalse;
import static org.junit.jupiter.api.Assertions.assertTrue;

import org.junit.jupiter.api.Test;

import io.lumipose.client.map.Beacon;
import io.lumipose.client.net.LocateResult;

class AlignmentGuideTest {
    private static final Beacon BENCH = new Beacon(0, new double[] {0, 0, 1}, 0, 0.174);
    private final AlignmentGuide guide = new AlignmentGuide(0.002, 0.5);

    private static LocateResult fix(double x, double y, double tiltDeg) {
        double t = Math.toRadians(tiltDeg);
        // Camera tilted about the map's X axis: optical axis (third column) leaves +Z by tiltDeg.
        return LocateResult.fromJson("{\"ok\": true, \"position_m\": [" + x + ", " + y + ", 0],"
                + " \"rotation_wc\": [[1, 0, 0], [0, " + Math.cos(t) + ", " + -Math.sin(t) + "], [0, "
                + Math.sin(t) + ", " + Math.cos(t) + "]]}");
    }

    @Test
    void centredAndLevelIsAligned() {
        AlignmentGuide.Alignment a = guide.evaluate(fix(0.001, -0.001, 0.2), BENCH);
        assertTrue(a.aligned, a.hint);
        assertEquals(0.2, a.tiltDeg, 1e-9);
        assertTrue(a.hint.startsWith("Aligned"));
    }

    @Test
    void offCentreSaysWhichWayToMove() {
        AlignmentGuide.Alignment a = guide.evaluate(fix(0.012, -0.003, 0.0), BENCH);
        assertFalse(a.aligned);
        assertEquals(0.012, a.offsetXM, 1e-12);
        assertTrue(a.hint.contains("12.0 mm towards -X"), a.hint);
        assertTrue(a.hint.contains("3.0 mm towards +Y"), a.hint);
    }

    @Test
    void tiltedIsNotAligned() {
        AlignmentGuide.Alignment a = guide.evaluate(fix(0, 0, 2.0), BENCH);
        assertFalse(a.aligned);
        assertTrue(a.hint.contains("tilted 2.00 deg"), a.hint);
    }

    @Test
    void noFixAsksForTheWholePanel() {
        AlignmentGuide.Alignment a = guide.evaluate(
                LocateResult.fromJson("{\"ok\": false, \"reason\": \"beacon_cut_off\"}"), BENCH);
        assertFalse(a.located);
        assertTrue(a.hint.contains("beacon_cut_off"));
    }
}
