package io.lumipose.client.net;

import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertFalse;
import static org.junit.jupiter.api.Assertions.assertTrue;

import java.util.ArrayList;
import java.util.Arrays;
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

class BurstUploaderTest {
    private final ExecutorService executor = Executors.newSingleThreadExecutor();
    private static final Intrinsics K = new Intrinsics(5, 5, 0.5, 0.5, null, null, null, null);

    @AfterEach
    void shutdown() {
        executor.shutdownNow();
    }

    /** Burst {@code b}: a pose frame at timestamp b * 10 and {@code ids} ID frames after it. */
    private static List<FrameUpload> burst(long b, int ids) {
        List<FrameUpload> frames = new ArrayList<>();
        frames.add(new FrameUpload(new byte[4], FrameMeta.builder(2, 2).camera(K).timestampNs(b * 10).build()));
        for (int i = 1; i <= ids; i++) {
            frames.add(new FrameUpload(new byte[4],
                    FrameMeta.builder(2, 2).camera(K).timestampNs(b * 10 + i).frameKind("id").build()));
        }
        return frames;
    }

    /** Blocks each upload until the test releases it; records what it sent and how many at once. */
    private static final class GatedUploader implements FrameUploader {
        final List<Long> sent = new CopyOnWriteArrayList<>();
        final Semaphore gate = new Semaphore(0);
        final AtomicInteger concurrent = new AtomicInteger();
        volatile int maxConcurrent;
        final CountDownLatch started = new CountDownLatch(1);
        volatile long failAt = -1;

        @Override
        public LocateResult upload(byte[] luma, FrameMeta meta) throws Exception {
            maxConcurrent = Math.max(maxConcurrent, concurrent.incrementAndGet());
            sent.add(meta.timestampNs);
            started.countDown();
            gate.acquire();
            concurrent.decrementAndGet();
            if (meta.timestampNs == failAt) {
                throw new java.io.IOException("boom");
            }
            return LocateResult.fromJson(LumiposeClientTest.OK);
        }
    }

    private static final class Recorder implements BurstUploader.Listener {
        final List<String> events = new CopyOnWriteArrayList<>();
        final Semaphore answered = new Semaphore(0);

        @Override
        public void onResult(FrameUpload frame, LocateResult result) {
            events.add((frame.isId() ? "id " : "pose ") + frame.meta.timestampNs);
            answered.release();
        }

        @Override
        public void onFailure(FrameUpload frame, Exception error) {
            events.add("failed " + frame.meta.timestampNs + ": " + error.getMessage());
            answered.release();
        }

        void await(int answers) throws InterruptedException {
            assertTrue(answered.tryAcquire(answers, 5, TimeUnit.SECONDS), "answers so far: " + events);
        }
    }

    @Test
    void oneBurstInFlightItsFramesInOrderAndTheNewestWaitingBurstWinsWhole() throws Exception {
        GatedUploader up = new GatedUploader();
        Recorder rec = new Recorder();
        BurstUploader u = new BurstUploader(up, executor, rec);
        assertTrue(u.hasRoom());
        assertTrue(u.submit(burst(1, 2)));
        assertTrue(up.started.await(5, TimeUnit.SECONDS));
        assertTrue(u.busy());
        assertTrue(u.hasRoom(), "the burst in flight leaves room for one waiting");
        u.submit(burst(2, 2));
        assertFalse(u.hasRoom());
        u.submit(burst(3, 2));
        up.gate.release(6);
        rec.await(6);
        assertEquals(Arrays.asList(10L, 11L, 12L, 30L, 31L, 32L), up.sent);
        assertEquals(Arrays.asList("pose 10", "id 11", "id 12", "pose 30", "id 31", "id 32"), rec.events);
        assertEquals(1, up.maxConcurrent);
        assertEquals(2, u.sentBursts());
        assertEquals(1, u.replacedBursts());
    }

    @Test
    void aFailedIdFrameSkipsItsBurstsOtherIdFramesButNotItsPoseFrame() throws Exception {
        GatedUploader up = new GatedUploader();
        up.failAt = 11;
        up.gate.release(100);
        Recorder rec = new Recorder();
        BurstUploader u = new BurstUploader(up, executor, rec);
        List<FrameUpload> idsFirst = burst(1, 3);
        idsFirst.add(idsFirst.remove(0)); // as the app sends a burst: its ID frames, then its pose frame
        u.submit(idsFirst);
        rec.await(2);
        u.submit(burst(2, 0));
        rec.await(1);
        assertEquals(Arrays.asList("failed 11: boom", "pose 10", "pose 20"), rec.events);
    }

    @Test
    void afterCloseNothingStartsAndTheFrameInFlightCompletes() throws Exception {
        GatedUploader up = new GatedUploader();
        Recorder rec = new Recorder();
        BurstUploader u = new BurstUploader(up, executor, rec);
        u.submit(burst(1, 2));
        assertTrue(up.started.await(5, TimeUnit.SECONDS));
        u.submit(burst(2, 0));
        u.close();
        assertFalse(u.submit(burst(3, 0)));
        assertFalse(u.hasRoom());
        up.gate.release(100);
        rec.await(1);
        executor.shutdown();
        assertTrue(executor.awaitTermination(5, TimeUnit.SECONDS));
        assertEquals(Arrays.asList("pose 10"), rec.events);
        assertEquals(Arrays.asList(10L), up.sent);
        assertEquals(1, u.replacedBursts(), "the waiting burst was dropped");
        assertFalse(u.busy());
    }

    @Test
    void aShutDownExecutorClosesTheUploaderInsteadOfThrowing() {
        executor.shutdown();
        BurstUploader u = new BurstUploader(new GatedUploader(), executor, new Recorder());
        assertFalse(u.submit(burst(1, 0)));
        assertFalse(u.hasRoom());
        assertFalse(u.busy());
    }

    /**
     * Many threads submit bursts at once while a pool thread sends: every burst sent is whole and
     * in order, never two in flight, and each burst is either sent or counted as replaced.
     */
    @Test
    void manyThreadsSubmittingNeverSplitOrInterleaveBursts() throws Exception {
        ExecutorService pool = Executors.newFixedThreadPool(4);
        FrameUploader up = new FrameUploader() {
            final AtomicInteger concurrent = new AtomicInteger();

            @Override
            public LocateResult upload(byte[] luma, FrameMeta meta) throws Exception {
                if (concurrent.incrementAndGet() != 1) {
                    throw new AssertionError("two frames in flight");
                }
                Thread.sleep(0, 200_000);
                concurrent.decrementAndGet();
                return LocateResult.fromJson(LumiposeClientTest.OK);
            }
        };
        List<Long> sent = new CopyOnWriteArrayList<>();
        List<String> failures = new CopyOnWriteArrayList<>();
        BurstUploader u = new BurstUploader(up, pool, new BurstUploader.Listener() {
            @Override
            public void onResult(FrameUpload frame, LocateResult result) {
                sent.add(frame.meta.timestampNs);
            }

            @Override
            public void onFailure(FrameUpload frame, Exception error) {
                failures.add(String.valueOf(error));
            }
        });
        int threads = 8;
        int perThread = 200;
        ExecutorService submitters = Executors.newFixedThreadPool(threads);
        CountDownLatch go = new CountDownLatch(1);
        for (int t = 0; t < threads; t++) {
            int first = t * perThread + 1;
            submitters.execute(() -> {
                try {
                    go.await();
                } catch (InterruptedException e) {
                    return;
                }
                for (int b = first; b < first + perThread; b++) {
                    u.submit(burst(b, 4));
                    u.hasRoom();
                }
            });
        }
        go.countDown();
        submitters.shutdown();
        assertTrue(submitters.awaitTermination(30, TimeUnit.SECONDS));
        long deadline = System.nanoTime() + TimeUnit.SECONDS.toNanos(30);
        while (u.busy() && System.nanoTime() < deadline) {
            Thread.sleep(5);
        }
        pool.shutdown();
        assertTrue(pool.awaitTermination(30, TimeUnit.SECONDS));
        assertEquals(List.of(), failures);
        assertEquals(0, sent.size() % 5);
        for (int i = 0; i < sent.size(); i += 5) {
            long pose = sent.get(i);
            assertEquals(0, pose % 10, "a burst starts with its pose frame: " + sent.subList(i, i + 5));
            for (int k = 1; k < 5; k++) {
                assertEquals(pose + k, sent.get(i + k).longValue(), "burst split or interleaved");
            }
        }
        assertEquals(threads * perThread, u.sentBursts() + u.replacedBursts());
        assertEquals(u.sentBursts() * 5, sent.size());
    }
}
