package io.lumipose.client.sensor;

import static org.junit.jupiter.api.Assertions.assertArrayEquals;
import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertNotNull;
import static org.junit.jupiter.api.Assertions.assertNull;
import static org.junit.jupiter.api.Assertions.assertTrue;

import java.util.ArrayList;
import java.util.List;
import java.util.concurrent.CountDownLatch;
import java.util.concurrent.ExecutorService;
import java.util.concurrent.Executors;
import java.util.concurrent.Future;
import java.util.concurrent.TimeUnit;

import org.junit.jupiter.api.Test;

class GravityHistoryTest {
    private static final long MS = 1_000_000L;

    /** Issue 12 item 9: the reading at the frame's SENSOR_TIMESTAMP, not the latest one. */
    @Test
    void gravityAtTheFramesTimestamp() {
        GravityHistory h = new GravityHistory(16, 50 * MS);
        h.addGravity(100 * MS, new float[] {0, 0, 9.8f});
        h.addGravity(110 * MS, new float[] {0, 9.8f, 0});
        h.addGravity(200 * MS, new float[] {9.8f, 0, 0}); // arrives before the frame's result
        // 102.5 ms: a quarter of the way from the first reading to the second.
        assertArrayEquals(new float[] {0, 2.45f, 7.35f}, h.gravityAt(102_500_000L), 1e-5f);
        assertArrayEquals(new float[] {0, 9.8f, 0}, h.gravityAt(110 * MS), 0f);
        assertArrayEquals(new float[] {9.8f, 0, 0}, h.latestGravity(), 0f);
        // Beyond the last reading but within the bound: the nearest.
        assertArrayEquals(new float[] {9.8f, 0, 0}, h.gravityAt(230 * MS), 0f);
        // Far from every reading: none, rather than a wrong one.
        assertNull(h.gravityAt(400 * MS));
        assertNull(h.gravityAt(10 * MS));
    }

    @Test
    void aGapWiderThanTheBoundTakesTheNearerSideOnly() {
        GravityHistory h = new GravityHistory(16, 50 * MS);
        h.addGravity(100 * MS, new float[] {0, 0, 9.8f});
        h.addGravity(300 * MS, new float[] {0, 9.8f, 0});
        assertArrayEquals(new float[] {0, 0, 9.8f}, h.gravityAt(140 * MS), 0f);
        assertNull(h.gravityAt(200 * MS));
    }

    @Test
    void rotationIsTheNearestNotAnAverage() {
        GravityHistory h = new GravityHistory(16, 50 * MS);
        float[] a = {1, 0, 0, 0, 1, 0, 0, 0, 1};
        float[] b = {0, -1, 0, 1, 0, 0, 0, 0, 1};
        h.addRotation(100 * MS, a);
        h.addRotation(110 * MS, b);
        assertArrayEquals(a, h.rotationAt(104 * MS), 0f);
        assertArrayEquals(b, h.rotationAt(106 * MS), 0f);
        GravityHistory.Attitude at = h.at(106 * MS);
        assertArrayEquals(b, at.rotationToEnu, 0f);
        assertNull(at.gravity);
    }

    /**
     * SENSOR_INFO_TIMESTAMP_SOURCE UNKNOWN: frame timestamps are on a clock of their own, not the
     * sensor events'; the latest reading is the best there is.
     */
    @Test
    void anUnknownTimestampSourceTakesTheLatest() {
        GravityHistory h = new GravityHistory(16, 50 * MS);
        h.addGravity(100 * MS, new float[] {0, 0, 9.8f});
        h.addGravity(110 * MS, new float[] {0, 9.8f, 0});
        long cameraClock = 5_000 * MS; // unrelated to the sensors' clock
        assertArrayEquals(new float[] {0, 9.8f, 0}, h.forFrame(cameraClock, false).gravity, 0f);
        assertNull(h.forFrame(cameraClock, true).gravity);
        assertArrayEquals(new float[] {0, 0, 9.8f}, h.forFrame(100 * MS, true).gravity, 0f);
    }

    @Test
    void theRingKeepsTheNewest() {
        GravityHistory h = new GravityHistory(4, 50 * MS);
        for (int i = 0; i < 10; i++) {
            h.addGravity(i * 10 * MS, new float[] {i, 0, 0});
        }
        assertArrayEquals(new float[] {9, 0, 0}, h.latestGravity(), 0f);
        assertArrayEquals(new float[] {6, 0, 0}, h.gravityAt(60 * MS), 0f);
        assertNull(h.gravityAt(0), "overwritten, and 50 ms from the oldest kept");
    }

    /** A sensor thread writes while camera threads read: no torn or missing samples, no exception. */
    @Test
    void manyThreadsAtOnce() throws Exception {
        final GravityHistory h = new GravityHistory(64, 5 * MS);
        final int samples = 20_000;
        final CountDownLatch go = new CountDownLatch(1);
        ExecutorService pool = Executors.newFixedThreadPool(6);
        List<Future<Integer>> readers = new ArrayList<Future<Integer>>();
        Future<?> writer = pool.submit(() -> {
            go.await();
            for (int i = 1; i <= samples; i++) {
                // Every reading has x = y = z, so a torn one (parts of two) would show.
                h.addGravity(i * MS, new float[] {i, i, i});
                h.addRotation(i * MS, new float[] {i, i, i, i, i, i, i, i, i});
            }
            return null;
        });
        for (int r = 0; r < 5; r++) {
            readers.add(pool.submit(() -> {
                go.await();
                int seen = 0;
                for (int i = 0; i < samples; i++) {
                    float[] latest = h.latestGravity();
                    float[] at = h.gravityAt((i + 1) * MS);
                    for (float[] g : new float[][] {latest, at}) {
                        if (g != null) {
                            assertEquals(g[0], g[1], 0f);
                            assertEquals(g[1], g[2], 0f);
                            seen++;
                        }
                    }
                }
                return seen;
            }));
        }
        go.countDown();
        writer.get(30, TimeUnit.SECONDS);
        int seen = 0;
        for (Future<Integer> f : readers) {
            seen += f.get(30, TimeUnit.SECONDS);
        }
        pool.shutdown();
        assertTrue(seen > 0);
        assertArrayEquals(new float[] {samples, samples, samples}, h.latestGravity(), 0f);
        assertNotNull(h.rotationAt(samples * MS));
    }
}
