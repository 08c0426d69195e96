package io.lumipose.client.net;

import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertFalse;
import static org.junit.jupiter.api.Assertions.assertTrue;

import java.util.List;
import java.util.concurrent.CopyOnWriteArrayList;
import java.util.concurrent.CountDownLatch;
import java.util.concurrent.ExecutorService;
import java.util.concurrent.Executors;
import java.util.concurrent.Semaphore;
import java.util.concurrent.TimeUnit;
import java.util.concurrent.atomic.AtomicInteger;

import org.junit.jupiter.api.AfterEach;
import org.junit.jupiter.api.Test;

import io.lumipose.client.camera.Intrinsics;
import io.lumipose.client.frame.FrameMeta;

class LatestFrameUploaderTest {
    private final ExecutorService executor = Executors.newSingleThreadExecutor();
    private final Intrinsics k = new Intrinsics(5, 5, 0.5, 0.5, null, null, null, null);

    @AfterEach
    void shutdown() {
        executor.shutdownNow();
    }

    private FrameMeta frame(long t) {
        return FrameMeta.builder(2, 2).camera(k).timestampNs(t).build();
    }

    /** An uploader that blocks each upload until the test releases it, and records what it sent. */
    private static final class GatedUploader implements FrameUploader {
        final List<Long> sent = new CopyOnWriteArrayList<>();
        final Semaphore gate = new Semaphore(0);
        final AtomicInteger concurrent = new AtomicInteger();
        volatile int maxConcurrent;
        final CountDownLatch started = new CountDownLatch(1);

        @Override
        public LocateResult upload(byte[] luma, FrameMeta meta) throws Exception {
            int now = concurrent.incrementAndGet();
            maxConcurrent = Math.max(maxConcurrent, now);
            sent.add(meta.timestampNs);
            started.countDown();
            gate.acquire();
            concurrent.decrementAndGet();
            if (meta.timestampNs == 99L) {
                throw new java.io.IOException("boom");
            }
            return LocateResult.fromJson(LumiposeClientTest.OK);
        }
    }

    @Test
    void oneInFlightAndTheNewestWaitingFrameWins() throws Exception {
        GatedUploader up = new GatedUploader();
        List<Long> results = new CopyOnWriteArrayList<>();
        CountDownLatch done = new CountDownLatch(2);
        LatestFrameUploader u = new LatestFrameUploader(up, executor, new LatestFrameUploader.Listener() {
            @Override
            public void onResult(FrameMeta meta, LocateResult result) {
                results.add(meta.timestampNs);
                done.countDown();
            }

            @Override
            public void onFailure(FrameMeta meta, Exception error) {
                throw new AssertionError(error);
            }
        });
        u.submit(new byte[4], frame(1));
        assertTrue(up.started.await(5, TimeUnit.SECONDS));
        assertTrue(u.busy());
        u.submit(new byte[4], frame(2));
        u.submit(new byte[4], frame(3));
        u.submit(new byte[4], frame(4));
        up.gate.release(2);
        assertTrue(done.await(5, TimeUnit.SECONDS));
        assertEquals(List.of(1L, 4L), up.sent);
        assertEquals(List.of(1L, 4L), results);
        assertEquals(2, u.droppedCount());
        assertEquals(2, u.sentCount());
        assertEquals(1, up.maxConcurrent);
        executor.shutdown();
        assertTrue(executor.awaitTermination(5, TimeUnit.SECONDS));
        assertFalse(u.busy());
    }

    @Test
    void failuresAreReportedAndTheNextFrameStillGoes() throws Exception {
        GatedUploader up = new GatedUploader();
        up.gate.release(10);
        List<String> events = new CopyOnWriteArrayList<>();
        CountDownLatch done = new CountDownLatch(2);
        LatestFrameUploader u = new LatestFrameUploader(up, executor, new LatestFrameUploader.Listener() {
            @Override
            public void onResult(FrameMeta meta, LocateResult result) {
                events.add("ok " + meta.timestampNs);
                done.countDown();
            }

            @Override
            public void onFailure(FrameMeta meta, Exception error) {
                events.add("failed " + meta.timestampNs + ": " + error.getMessage());
                done.countDown();
            }
        });
        u.submit(new byte[4], frame(99));
        while (u.busy()) {
            Thread.sleep(1);
        }
        u.submit(new byte[4], frame(5));
        assertTrue(done.await(5, TimeUnit.SECONDS));
        assertEquals(List.of("failed 99: boom", "ok 5"), events);
    }

    @Test
    void closedUploaderRefusesFrames() {
        LatestFrameUploader u = new LatestFrameUploader(new GatedUploader(), executor,
                new LatestFrameUploader.Listener() {
                    @Override
                    public void onResult(FrameMeta meta, LocateResult result) {
                    }

                    @Override
                    public void onFailure(FrameMeta meta, Exception error) {
                    }
                });
        u.close();
        assertFalse(u.submit(new byte[4], frame(1)));
        assertEquals(0, u.sentCount());
    }
}
