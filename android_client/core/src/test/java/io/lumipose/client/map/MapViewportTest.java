package io.lumipose.client.map;

import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertThrows;
import static org.junit.jupiter.api.Assertions.assertTrue;

import java.util.Arrays;
import java.util.Collections;
import java.util.List;

import org.junit.jupiter.api.Test;

class MapViewportTest {
    private static final RoomMap OFFICE = new RoomMap("office", Arrays.asList(
            new Beacon(5, new double[] {0.6, 0.9, 2.72}, 0, 0.174),
            new Beacon(22, new double[] {1.8, 2.7, 2.72}, 0, 0.174)));

    @Test
    void everythingFitsInsideTheMarginsAndNorthIsUp() {
        List<double[]> track = Collections.singletonList(new double[] {-0.5, 3.5, 0});
        MapViewport v = MapViewport.fit(OFFICE, track, 400, 800, 20, 1.0);
        for (double[] p : new double[][] {{-0.5, 3.5}, {0.513, 0.813}, {1.887, 2.787}}) {
            double x = v.screenX(p[0]);
            double y = v.screenY(p[1]);
            assertTrue(x >= 20 - 1e-9 && x <= 380 + 1e-9, "x " + x);
            assertTrue(y >= 20 - 1e-9 && y <= 780 + 1e-9, "y " + y);
        }
        assertTrue(v.screenY(2.7) < v.screenY(0.9), "map +Y is drawn upwards");
        assertEquals(v.screenX(1.0) - v.screenX(0.0), v.screenY(0.0) - v.screenY(1.0), 1e-9);
    }

    @Test
    void aLoneBeaconIsShownWithTheMinimumSpan() {
        RoomMap one = new RoomMap("bench", Collections.singletonList(new Beacon(0, new double[] {0, 0, 1}, 0, 0.174)));
        MapViewport v = MapViewport.fit(one, Collections.<double[]>emptyList(), 500, 500, 0, 1.0);
        assertEquals(500, v.pxPerM, 1e-9);
        assertEquals(250, v.screenX(0), 1e-9);
        assertThrows(IllegalArgumentException.class,
                () -> MapViewport.fit(one, Collections.<double[]>emptyList(), 10, 10, 5, 1.0));
    }

    @Test
    void trackKeepsTheNewestPoints() {
        Track t = new Track(2);
        t.add(new double[] {1, 0, 0});
        t.add(new double[] {2, 0, 0});
        t.add(new double[] {3, 0, 0});
        assertEquals(2, t.snapshot().size());
        assertEquals(2.0, t.snapshot().get(0)[0], 0);
        assertEquals(3.0, t.snapshot().get(1)[0], 0);
    }
}
