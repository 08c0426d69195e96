package io.lumipose.client.sensor;

import static org.junit.jupiter.api.Assertions.assertArrayEquals;
import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertSame;

import org.junit.jupiter.api.Test;

/** Issue 12 item 9: gravity from the accelerometer on phones without TYPE_GRAVITY. */
class LowPassGravityTest {
    private static final long MS = 1_000_000L;

    @Test
    void theFirstReadingStartsTheFilter() {
        LowPassGravity f = new LowPassGravity(200 * MS);
        assertArrayEquals(new float[] {0, 0, 9.81f}, f.update(0, new float[] {0, 0, 9.81f}), 0f);
    }

    /** Weight dt / (tau + dt): 10 ms steps with tau 190 ms move 1/20 of the way. */
    @Test
    void eachReadingMovesByItsShareOfTheTimeConstant() {
        LowPassGravity f = new LowPassGravity(190 * MS);
        f.update(0, new float[] {0, 0, 10});
        assertArrayEquals(new float[] {1, 0, 9.5f}, f.update(10 * MS, new float[] {20, 0, 0}), 1e-5f);
    }

    @Test
    void shakeAveragesAwayGravityStays() {
        LowPassGravity f = new LowPassGravity();
        float[] g = null;
        for (int i = 0; i < 400; i++) { // 2 s at 200 Hz, a 10 Hz tremor of 3 m/s^2 on x
            float shake = (float) (3 * Math.sin(2 * Math.PI * 10 * i * 0.005));
            g = f.update(i * 5 * MS, new float[] {shake, 0, 9.81f});
        }
        // First order at 10 Hz, tau 0.2 s: gain 1 / sqrt(1 + (2 pi 10 0.2)^2) = 0.08, so 3 m/s^2 -> 0.24.
        assertEquals(0, g[0], 0.25);
        assertEquals(9.81, g[2], 1e-4);
    }

    @Test
    void aLongPauseRestarts() {
        LowPassGravity f = new LowPassGravity(200 * MS);
        f.update(0, new float[] {0, 0, 9.81f});
        assertArrayEquals(new float[] {9.81f, 0, 0}, f.update(5_000 * MS, new float[] {9.81f, 0, 0}), 0f);
    }

    /** The sensor thread's form: the same filter into one buffer, which the caller then hands on. */
    @Test
    void intoABufferTheSameValues() {
        LowPassGravity fresh = new LowPassGravity();
        LowPassGravity buffered = new LowPassGravity();
        float[] out = new float[3];
        for (int i = 0; i < 50; i++) {
            float[] a = {(float) Math.sin(i), 0.5f, 9.81f};
            float[] expected = fresh.update(i * 5 * MS, a);
            assertSame(out, buffered.update(i * 5 * MS, a, out));
            assertArrayEquals(expected, out, 0f);
        }
    }
}
