package io.lumipose.client.bench;

import static org.junit.jupiter.api.Assertions.assertArrayEquals;
import static org.junit.jupiter.api.Assertions.assertEquals;

import org.junit.jupiter.api.Test;

class TestBenchGridTest {
    @Test
    void papersGridIsWalkedFromTopLeftToBottomRight() {
        TestBenchGrid g = TestBenchGrid.paper();
        assertEquals(391, g.size());
        assertEquals("-8,11", g.cell(0).label());
        assertEquals("8,11", g.cell(16).label());
        assertEquals("-8,10", g.cell(17).label());
        assertEquals("0,0", g.cell(195).label());
        assertEquals("8,-11", g.cell(390).label());
        assertEquals(195, g.indexOf("0,0"));
        assertEquals(-1, g.indexOf("9,0"));
    }

    @Test
    void cellPositionAndErrorAreInTheMapFrame() {
        BenchCell c = TestBenchGrid.paper().cell(TestBenchGrid.paper().indexOf("3,-4"));
        assertArrayEquals(new double[] {0.15, -0.2, 0}, c.positionM(), 1e-12);
        assertEquals(5.0, c.horizontalErrorMm(new double[] {0.153, -0.204, 0.01}), 1e-9);
    }
}
