package io.lumipose.client.sensor;

import static org.junit.jupiter.api.Assertions.assertArrayEquals;
import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertNull;
import static org.junit.jupiter.api.Assertions.assertThrows;
import static org.junit.jupiter.api.Assertions.assertTrue;

import java.util.ArrayList;
import java.util.List;
import java.util.concurrent.CountDownLatch;
import java.util.concurrent.ExecutorService;
import java.util.concurrent.Executors;
import java.util.concurrent.Future;
import java.util.concurrent.TimeUnit;

import org.junit.jupiter.api.Test;

class GyroHistoryTest {
    private static final long MS = 1_000_000L;

    /** The mean over the readout, from the readings inside it only. */
    @Test
    void theMeanOfTheReadingsInsideTheWindow() {
        GyroHistory h = new GyroHistory(16, 20 * MS);
        h.add(95 * MS, new float[] {9, 9, 9}); // before the window: left out
        h.add(100 * MS, new float[] {0.1f, 0, -1});
        h.add(105 * MS, new float[] {0.2f, 0, -1});
        h.add(110 * MS, new float[] {0.6f, 0.3f, -1});
        h.add(131 * MS, new float[] {9, 9, 9}); // after it: left out
        assertArrayEquals(new float[] {0.3f, 0.1f, -1}, h.meanOver(100 * MS, 130 * MS), 1e-6f);
        // A window of one instant on a reading is that reading.
        assertArrayEquals(new float[] {0.2f, 0, -1}, h.meanOver(105 * MS, 105 * MS), 0f);
    }

    /** A short readout between two readings takes the nearer one, when it is near enough. */
    @Test
    void aWindowWithoutReadingsTakesTheNearestWithinTheGap() {
        GyroHistory h = new GyroHistory(16, 20 * MS);
        h.add(100 * MS, new float[] {1, 0, 0});
        h.add(120 * MS, new float[] {0, 1, 0});
        assertArrayEquals(new float[] {1, 0, 0}, h.meanOver(102 * MS, 108 * MS), 0f);
        assertArrayEquals(new float[] {0, 1, 0}, h.meanOver(112 * MS, 115 * MS), 0f);
        assertArrayEquals(new float[] {0, 1, 0}, h.meanOver(135 * MS, 150 * MS), 0f, "15 ms after the last");
    }

    @Test
    void noneWhenNoReadingIsNear() {
        GyroHistory h = new GyroHistory(16, 20 * MS);
        assertNull(h.meanOver(100 * MS, 130 * MS), "before any reading");
        h.add(100 * MS, new float[] {1, 0, 0});
        assertNull(h.meanOver(121 * MS, 150 * MS), "stale: 21 ms before the window");
        assertNull(h.meanOver(50 * MS, 79 * MS), "21 ms after it");
    }

    @Test
    void theRingKeepsTheNewest() {
        GyroHistory h = new GyroHistory(4, 20 * MS);
        for (int i = 0; i < 10; i++) {
            h.add(i * 10 * MS, new float[] {i, 0, 0});
        }
        // Readings 6..9 are kept: the window over all ten sees only them.
        assertArrayEquals(new float[] {7.5f, 0, 0}, h.meanOver(0, 100 * MS), 1e-6f);
    }

    /**
     * SENSOR_INFO_TIMESTAMP_SOURCE UNKNOWN: the frame's readout cannot be found among the readings,
     * and the latest reading is no frame's rate, so there is none.
     */
    @Test
    void anUnknownTimestampSourceGivesNoRate() {
        GyroHistory h = new GyroHistory(16, 20 * MS);
        h.add(100 * MS, new float[] {1, 2, 3});
        assertNull(h.forFrame(100 * MS, 130 * MS, false));
        assertArrayEquals(new float[] {1, 2, 3}, h.forFrame(100 * MS, 130 * MS, true), 0f);
    }

    @Test
    void badInputIsRejected() {
        GyroHistory h = new GyroHistory(16, 20 * MS);
        assertThrows(IllegalArgumentException.class, () -> h.add(1, new float[] {1, 2}));
        assertThrows(IllegalArgumentException.class, () -> h.meanOver(20, 10));
        assertThrows(IllegalArgumentException.class, () -> new GyroHistory(1, 20 * MS));
        assertThrows(IllegalArgumentException.class, () -> new GyroHistory(16, 0));
    }

    /** The sensor thread writes while camera threads read: no torn means, no exception. */
    @Test
    void manyThreadsAtOnce() throws Exception {
        final GyroHistory h = new GyroHistory(64, 5 * MS);
        final int samples = 20_000;
        final CountDownLatch go = new CountDownLatch(1);
        ExecutorService pool = Executors.newFixedThreadPool(6);
        List<Future<Integer>> readers = new ArrayList<Future<Integer>>();
        Future<?> writer = pool.submit(() -> {
            go.await();
            for (int i = 1; i <= samples; i++) {
                // x = y = z in every reading, so any mean has x = y = z unless one was torn.
                h.add(i * MS, new float[] {i, i, i});
            }
            return null;
        });
        for (int r = 0; r < 5; r++) {
            readers.add(pool.submit(() -> {
                go.await();
                int seen = 0;
                for (int i = 0; i < samples; i++) {
                    // A readout's window (mostly empty: the readers outrun the writer) and the whole ring.
                    float[][] means = {h.meanOver(i * MS, (i + 30) * MS), h.meanOver(0, samples * MS)};
                    for (float[] mean : means) {
                        if (mean != null) {
                            assertEquals(mean[0], mean[1], 0f);
                            assertEquals(mean[1], mean[2], 0f);
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
        // The last 31 readings, samples - 30 .. samples: their mean is the middle one.
        float mid = samples - 15;
        assertArrayEquals(new float[] {mid, mid, mid}, h.meanOver((samples - 30) * MS, samples * MS), 1e-3f);
    }
}
