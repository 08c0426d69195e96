package io.lumipose.client.sensor;

import static org.junit.jupiter.api.Assertions.assertArrayEquals;
import static org.junit.jupiter.api.Assertions.assertTrue;

import java.lang.management.ManagementFactory;

import org.junit.jupiter.api.Test;

/**
 * Issue 26: the sensors deliver about 300 events a second (gravity and rotation at 50 Hz, the
 * gyroscope at 200 Hz); once the histories' rings are full, keeping one allocates nothing (the
 * garbage collector's pauses land on the camera and upload threads too). The histories still copy
 * what they keep: SensorEvent.values, like the listener's buffers, is reused for the next event.
 */
class SensorAllocationTest {
    private static final int EVENTS = 100_000;

    private static long allocatedBytes() {
        return ((com.sun.management.ThreadMXBean) ManagementFactory.getThreadMXBean())
                .getThreadAllocatedBytes(Thread.currentThread().getId());
    }

    @Test
    void keepingAReadingAllocatesNothingOnceTheRingsAreFull() {
        GravityHistory attitude = new GravityHistory();
        GyroHistory rates = new GyroHistory();
        LowPassGravity lowPass = new LowPassGravity();
        float[] values = new float[3];
        float[] matrix = new float[9];
        float[] filtered = new float[3];
        feed(attitude, rates, lowPass, values, matrix, filtered, 0, 20_000); // the rings full, add() compiled
        long before = allocatedBytes();
        feed(attitude, rates, lowPass, values, matrix, filtered, 20_000, EVENTS);
        long bytes = allocatedBytes() - before;
        // A copy each would be 32-56 bytes an event, 13 MB in all; allow the measurement's own few bytes.
        assertTrue(bytes < 64 * 1024, bytes + " bytes for " + (4L * EVENTS) + " readings kept");
    }

    @Test
    void theHistoriesKeepTheirOwnCopyOfAReusedArray() {
        GravityHistory attitude = new GravityHistory(4, 100_000_000L);
        GyroHistory rates = new GyroHistory(4, 20_000_000L);
        float[] values = {1, 2, 3};
        float[] matrix = {1, 0, 0, 0, 1, 0, 0, 0, 1};
        for (int i = 0; i < 6; i++) { // past the capacity: the rows are reused
            values[0] = i;
            attitude.addGravity(i * 10_000_000L, values);
            rates.add(i * 10_000_000L, values);
            matrix[1] = i;
            attitude.addRotation(i * 10_000_000L, matrix);
        }
        values[0] = 99;
        matrix[1] = 99;
        assertArrayEquals(new float[] {4, 2, 3}, attitude.gravityAt(40_000_000L), 0f);
        assertArrayEquals(new float[] {5, 2, 3}, rates.meanOver(50_000_000L, 50_000_000L), 0f);
        assertArrayEquals(new float[] {1, 3, 0, 0, 1, 0, 0, 0, 1}, attitude.rotationAt(30_000_000L), 0f);
        float[] latest = attitude.latestGravity();
        latest[0] = -1; // a reader's copy is its own too
        assertArrayEquals(new float[] {5, 2, 3}, attitude.latestGravity(), 0f);
    }

    /** What the app's listener does per event: one reused array for each kind. */
    private static void feed(GravityHistory attitude, GyroHistory rates, LowPassGravity lowPass, float[] values,
                             float[] matrix, float[] filtered, int from, int to) {
        for (int i = from; i < to; i++) {
            long t = i * 5_000_000L;
            values[0] = i % 7;
            values[2] = 9.81f;
            attitude.addGravity(t, values);
            rates.add(t, values);
            matrix[0] = i % 5;
            attitude.addRotation(t, matrix);
            attitude.addGravity(t + 1, lowPass.update(t, values, filtered));
        }
    }
}
