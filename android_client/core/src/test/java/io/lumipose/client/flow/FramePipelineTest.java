package io.lumipose.client.flow;

import static org.junit.jupiter.api.Assertions.assertArrayEquals;
import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertFalse;
import static org.junit.jupiter.api.Assertions.assertNotNull;
import static org.junit.jupiter.api.Assertions.assertNull;
import static org.junit.jupiter.api.Assertions.assertTrue;

import java.nio.ByteBuffer;
import java.util.ArrayList;
import java.util.Arrays;
import java.util.Collections;
import java.util.List;
import java.util.Map;
import java.util.Random;
import java.util.concurrent.CopyOnWriteArrayList;
import java.util.concurrent.ExecutorService;
import java.util.concurrent.Executors;
import java.util.concurrent.Semaphore;
import java.util.concurrent.TimeUnit;

import org.json.JSONArray;
import org.junit.jupiter.api.Test;

import io.lumipose.client.camera.CameraFacts;
import io.lumipose.client.camera.Devices;
import io.lumipose.client.camera.FrameResult;
import io.lumipose.client.capture.CaptureOptions;
import io.lumipose.client.capture.CapturePlan;
import io.lumipose.client.capture.FrameDescriber;
import io.lumipose.client.frame.BeaconWindow;
import io.lumipose.client.frame.FrameMeta;
import io.lumipose.client.frame.LumaPlane;
import io.lumipose.client.frame.Window;
import io.lumipose.client.net.FrameUploader;
import io.lumipose.client.net.LocateResult;
import io.lumipose.client.protocol.CaptureProtocol;
import io.lumipose.client.sensor.GravityHistory;
import io.lumipose.client.sensor.GyroHistory;

class FramePipelineTest {
    private static final int W = 640;
    private static final int H = 480;
    private static final long FRAME_NS = 33_000_000L;
    private static final java.util.concurrent.Executor DIRECT = Runnable::run;
    private static final String OK =
            "{\"schema\": \"lumipose.result/1\", \"ok\": true, \"position_m\": [0.1, 0.2, 0.0]}";

    private static CapturePlan plan(int beacons) throws Exception {
        CameraFacts facts = Devices.load(Devices.LOGICAL);
        return CapturePlan.plan(facts, new CaptureOptions(CaptureProtocol.POSE_EXPOSURE_NS,
                CaptureProtocol.ID_EXPOSURE_NS, beacons, 2.0, (long) W * H));
    }

    /** Records what was uploaded and what the listener heard. */
    private static final class Recorder implements FrameUploader, FramePipeline.Listener {
        final List<FrameMeta> sent = new CopyOnWriteArrayList<>();
        final List<byte[]> bodies = new CopyOnWriteArrayList<>();
        final List<String> heard = new CopyOnWriteArrayList<>();
        final Semaphore gate;

        Recorder(Semaphore gate) {
            this.gate = gate;
        }

        @Override
        public LocateResult upload(byte[] luma, FrameMeta meta) throws Exception {
            sent.add(meta);
            bodies.add(luma);
            if (gate != null) {
                gate.acquire();
            }
            return LocateResult.fromJson(OK);
        }

        @Override
        public void onPoseResult(FrameMeta meta, LocateResult result) {
            heard.add("pose " + meta.timestampNs);
        }

        @Override
        public void onIdResult(FrameMeta meta, LocateResult result) {
            heard.add("id " + meta.timestampNs);
        }

        @Override
        public void onDropped(String reason) {
            heard.add("dropped: " + reason);
        }

        @Override
        public void onFailure(FrameMeta meta, Exception error) {
            heard.add("failed " + meta.timestampNs);
        }
    }

    /** One captured frame: its result and its Y plane (a bright panel at (px, py), padded rows). */
    private static final class Frame {
        final FrameResult result;
        final byte[] packed;

        Frame(FrameResult result, byte[] packed) {
            this.result = result;
            this.packed = packed;
        }

        long t() {
            return result.timestampNs;
        }

        void image(FrameSink sink) {
            int stride = W + 32;
            ByteBuffer plane = ByteBuffer.allocateDirect(stride * H);
            for (int row = 0; row < H; row++) {
                plane.position(row * stride);
                plane.put(packed, row * W, W);
            }
            plane.position(0);
            sink.onImage(t(), plane, W, H, stride, 1);
            for (int i = 0; i < plane.capacity(); i++) {
                plane.put(i, (byte) 0); // the camera reuses the buffer: nothing may be kept of it
            }
        }
    }

    private static byte[] panelAt(int px, int py, int level) {
        byte[] p = new byte[W * H];
        Arrays.fill(p, (byte) 12);
        for (int y = py; y < py + 40; y++) {
            for (int x = px; x < px + 40; x++) {
                p[y * W + x] = (byte) level;
            }
        }
        return p;
    }

    /** Bursts of a pose frame and the plan's ID frames, the panel moving 3 px a burst. */
    private static List<Frame> bursts(CapturePlan plan, int count) {
        List<Frame> frames = new ArrayList<>();
        long t = 1_000_000_000L;
        for (int b = 0; b < count; b++) {
            byte[] pose = panelAt(200 + 3 * b, 150, 250);
            frames.add(new Frame(result(plan, "pose", t), pose));
            t += FRAME_NS;
            for (int i = 0; i < plan.idFramesPerBurst; i++) {
                frames.add(new Frame(result(plan, "id", t), panelAt(200 + 3 * b, 150, 90)));
                t += FRAME_NS;
            }
        }
        return frames;
    }

    private static FrameResult result(CapturePlan plan, String kind, long t) {
        return FrameResult.builder(t).request(kind).exposureNs(plan.spec(kind).exposureNs)
                .sensitivityIso(plan.spec(kind).sensitivityIso).rollingShutterSkewNs(20_000_000L)
                .focalLengthMm(4.8).build();
    }

    private static FramePipeline pipeline(CapturePlan plan, Recorder r, java.util.concurrent.Executor e) {
        return pipeline(Devices.load(Devices.LOGICAL), plan, r, e);
    }

    private static FramePipeline pipeline(CameraFacts facts, CapturePlan plan, Recorder r,
                                          java.util.concurrent.Executor e) {
        return FramePipeline.forCamera(facts, plan, null, new GravityHistory(), new GyroHistory(), r, e, r);
    }

    /** The fixture's camera as a LIMITED device without per-frame control. */
    private static CameraFacts lagging() {
        return Devices.load(Devices.LOGICAL).toBuilder().syncMaxLatency(CameraFacts.SYNC_UNKNOWN).build();
    }

    /** An exposure neither request asked for: the sensor between the camera's old settings and the burst's. */
    private static final long TRANSITION_EXPOSURE_NS = 4_000_000L;

    /**
     * What a device whose settings lag {@code lag} frames delivers for {@code exposed} (the bursts
     * as their exposures run): each frame tagged with the request submitted for it, the repeating
     * burst {@code lag} places ahead of its exposure, after {@code lag} frames still taken with the
     * camera's earlier settings.
     */
    private static List<Frame> withSettingsLag(CapturePlan plan, List<Frame> exposed, int lag) {
        int n = plan.idFramesPerBurst + 1;
        List<Frame> out = new ArrayList<>();
        for (int i = 0; i < lag; i++) {
            String tag = i % n == 0 ? "pose" : "id";
            long t = exposed.get(0).t() - (lag - i) * FRAME_NS;
            out.add(new Frame(result(plan, tag, t).toBuilder().exposureNs(TRANSITION_EXPOSURE_NS).build(),
                    panelAt(200, 150, 160)));
        }
        for (int i = 0; i < exposed.size(); i++) {
            String tag = (i + lag) % n == 0 ? "pose" : "id";
            Frame f = exposed.get(i);
            out.add(new Frame(f.result.toBuilder().request(tag).build(), f.packed));
        }
        return out;
    }

    /** Feeds the frames with each image {@code lag} frames after its result (negative: before). */
    private static void feed(FrameSink sink, List<Frame> frames, int lag) {
        int n = frames.size();
        for (int step = Math.min(0, lag); step < n + Math.max(0, lag); step++) {
            if (lag >= 0) {
                if (step < n) {
                    sink.onResult(frames.get(step).result);
                }
                if (step - lag >= 0 && step - lag < n) {
                    frames.get(step - lag).image(sink);
                }
            } else {
                if (step - lag < n) {
                    frames.get(step - lag).image(sink);
                }
                if (step >= 0 && step < n) {
                    sink.onResult(frames.get(step).result);
                }
            }
        }
    }

    /** The frames in the order the server needs them: each burst's ID frames, then its pose frame. */
    private static List<Frame> uploadOrder(CapturePlan plan, List<Frame> frames) {
        int n = plan.idFramesPerBurst + 1;
        List<Frame> order = new ArrayList<>();
        for (int b = 0; b < frames.size(); b += n) {
            order.addAll(frames.subList(b + 1, b + n));
            order.add(frames.get(b));
        }
        return order;
    }

    private static void assertBurstsWentWhole(CapturePlan plan, List<Frame> captured, Recorder r) {
        List<Frame> frames = uploadOrder(plan, captured);
        assertEquals(frames.size(), r.sent.size(), "every frame goes: " + r.heard);
        for (int i = 0; i < frames.size(); i++) {
            Frame f = frames.get(i);
            FrameMeta m = r.sent.get(i);
            assertEquals(f.t(), m.timestampNs.longValue(), "each burst's ID frames in capture order, then its pose");
            Frame pose = frames.get(i - i % (plan.idFramesPerBurst + 1) + plan.idFramesPerBurst);
            assertEquals(f == pose ? "pose" : "id", m.frameKind, "the kind its exposure shows");
            Window panel = BeaconWindow.find(pose.packed, W, H);
            Window w = f == pose ? panel : FramePipeline.idWindow(panel, W, H);
            assertNotNull(m.crop);
            assertEquals(w, new Window(m.crop.x, m.crop.y, m.crop.x + m.width, m.crop.y + m.height),
                    "the pose frame's beacon window, grown for its ID frames");
            assertTrue(w.contains(panel));
            assertEquals(W, m.fullWidth());
            assertArrayEquals(LumaPlane.copyWindow(ByteBuffer.wrap(f.packed), W, H, W, 1, w), r.bodies.get(i));
        }
    }

    @Test
    void aBurstGoesWholeInOrderWithItsPoseWindowWhicheverHalfOfAFrameComesFirst() throws Exception {
        CapturePlan plan = plan(4);
        assertEquals(CaptureProtocol.ID_BURST_FRAMES, plan.idFramesPerBurst);
        for (int lag : new int[] {0, 1, 3, -1, -2, -3}) {
            List<Frame> frames = bursts(plan, 3);
            Recorder r = new Recorder(null);
            FramePipeline p = pipeline(plan, r, DIRECT);
            feed(p, frames, lag);
            assertBurstsWentWhole(plan, frames, r);
            assertEquals(Collections.emptyMap(), p.dropCounts(), "lag " + lag);
            long poses = r.heard.stream().filter(s -> s.startsWith("pose")).count();
            assertEquals(3, poses, "one position a burst; ID frames' answers are never positions");
            assertEquals(3 * plan.idFramesPerBurst, r.heard.stream().filter(s -> s.startsWith("id")).count());
        }
    }

    @Test
    void resultsAndImagesInAnyOrderWithinAFewFramesGiveTheSameUploads() throws Exception {
        CapturePlan plan = plan(4);
        Random rng = new Random(5);
        for (int trial = 0; trial < 20; trial++) {
            List<Frame> frames = bursts(plan, 4);
            // the camera delivers results in order and images in order, interleaved arbitrarily
            List<Runnable> calls = new ArrayList<>();
            Recorder r = new Recorder(null);
            FramePipeline p = pipeline(plan, r, DIRECT);
            int results = 0;
            int images = 0;
            while (results < frames.size() || images < frames.size()) {
                boolean result = images == frames.size() || (results < frames.size() && results - images < 3
                        && (images - results >= 3 || rng.nextBoolean()));
                if (result) {
                    p.onResult(frames.get(results++).result);
                } else {
                    frames.get(images++).image(p);
                }
            }
            assertBurstsWentWhole(plan, frames, r);
            assertEquals(Collections.emptyMap(), p.dropCounts(), "trial " + trial);
            assertTrue(calls.isEmpty());
        }
    }

    @Test
    void aOneBeaconMapSendsPoseFramesOnlyEachItsOwnBurst() throws Exception {
        CapturePlan plan = plan(1);
        assertNull(plan.id);
        assertEquals(0, plan.idFramesPerBurst);
        List<Frame> frames = bursts(plan, 4);
        Recorder r = new Recorder(null);
        FramePipeline p = pipeline(plan, r, DIRECT);
        feed(p, frames, 1);
        assertBurstsWentWhole(plan, frames, r);
        assertEquals(Arrays.asList("pose " + frames.get(0).t(), "pose " + frames.get(1).t(),
                "pose " + frames.get(2).t(), "pose " + frames.get(3).t()), r.heard);
    }

    @Test
    void aBurstIsDroppedWholeAtItsPoseFrameWhileTheUploaderHoldsOneWaiting() throws Exception {
        CapturePlan plan = plan(4);
        int n = plan.idFramesPerBurst + 1;
        List<Frame> frames = bursts(plan, 3);
        Recorder r = new Recorder(new Semaphore(0));
        ExecutorService network = Executors.newSingleThreadExecutor();
        try {
            FramePipeline p = pipeline(plan, r, network);
            feed(p, frames.subList(0, n), 0);
            long deadline = System.nanoTime() + TimeUnit.SECONDS.toNanos(10);
            while (r.sent.isEmpty() && System.nanoTime() < deadline) {
                Thread.sleep(1); // until the uploader has taken burst 1
            }
            feed(p, frames.subList(n, 3 * n), 0);
            // burst 1 in flight, burst 2 waiting, burst 3 dropped whole
            assertEquals(Collections.singletonMap(FramePipeline.DROP_UPLOADER_BUSY, (long) n), p.dropCounts());
            r.gate.release(100);
            deadline = System.nanoTime() + TimeUnit.SECONDS.toNanos(10);
            while (p.uploading() && System.nanoTime() < deadline) {
                Thread.sleep(2);
            }
            assertEquals(2 * n, r.sent.size());
            assertEquals(frames.get(n).t(), r.sent.get(2 * n - 1).timestampNs.longValue(), "burst 2's pose frame");
        } finally {
            network.shutdownNow();
        }
    }

    /** The pixel work done for the frames from {@code fromNs} on, counted; the rest is done uncounted. */
    private static final class CountingWork implements PlaneWork {
        final long fromNs;
        volatile boolean counting;
        int searches;
        int copies;
        int levels;

        CountingWork(long fromNs) {
            this.fromNs = fromNs;
        }

        /** The sink whose calls for frames from {@code fromNs} on are counted (a call's work is its frame's). */
        FrameSink counted(FrameSink sink) {
            return new FrameSink() {
                @Override
                public void onResult(FrameResult result) {
                    counting = result.timestampNs >= fromNs;
                    sink.onResult(result);
                }

                @Override
                public void onImage(long timestampNs, ByteBuffer yPlane, int width, int height, int rowStride,
                                    int pixelStride) {
                    counting = timestampNs >= fromNs;
                    sink.onImage(timestampNs, yPlane, width, height, rowStride, pixelStride);
                }
            };
        }

        @Override
        public Window findPanel(ByteBuffer plane, int width, int height, int rowStride, int pixelStride) {
            searches += counting ? 1 : 0;
            return PlaneWork.PIXELS.findPanel(plane, width, height, rowStride, pixelStride);
        }

        @Override
        public byte[] copyWindow(ByteBuffer plane, int width, int height, int rowStride, int pixelStride, Window w) {
            copies += counting ? 1 : 0;
            return PlaneWork.PIXELS.copyWindow(plane, width, height, rowStride, pixelStride, w);
        }

        @Override
        public double[] levels(ByteBuffer plane, int width, int height, int rowStride, int pixelStride) {
            levels += counting ? 1 : 0;
            return PlaneWork.PIXELS.levels(plane, width, height, rowStride, pixelStride);
        }
    }

    /**
     * Battery and heat (issue 26): a burst the uploader cannot take (one burst in flight, the one
     * before it waiting) is decided at its pose frame's first half, before any search or copy, in
     * either arrival order: at an image that comes before its result too, even while the burst
     * before it is still being gathered (it will take the waiting place).
     */
    @Test
    void aBurstTheUploaderCannotTakeIsNeitherSearchedNorCopiedWhicheverHalfComesFirst() throws Exception {
        CapturePlan plan = plan(4);
        CameraFacts facts = Devices.load(Devices.LOGICAL);
        int n = plan.idFramesPerBurst + 1;
        for (int lag : new int[] {0, 1, 3, -1, -2, -3}) {
            List<Frame> frames = bursts(plan, 3);
            Recorder r = new Recorder(new Semaphore(0));
            CountingWork work = new CountingWork(frames.get(2 * n).t());
            ExecutorService network = Executors.newSingleThreadExecutor();
            try {
                FramePipeline p = new FramePipeline(new FrameDescriber(facts, plan, null), new GravityHistory(),
                        new GyroHistory(), true, plan.idFramesPerBurst, r, network, r, work);
                feed(p, frames.subList(0, n), 0);
                long deadline = System.nanoTime() + TimeUnit.SECONDS.toNanos(10);
                while (r.sent.isEmpty() && System.nanoTime() < deadline) {
                    Thread.sleep(1); // until the uploader has taken burst 1 (and is held there)
                }
                feed(work.counted(p), frames.subList(n, 3 * n), lag); // burst 2 waits, burst 3 has no room
                String where = "lag " + lag + ": " + r.heard;
                assertEquals(0, work.searches, "panel searches for the dropped burst, " + where);
                assertEquals(0, work.copies, "copies for the dropped burst, " + where);
                assertEquals(0, work.levels, "grey levels for the dropped burst, " + where);
                assertEquals(Collections.singletonMap(FramePipeline.DROP_UPLOADER_BUSY, (long) n), p.dropCounts(),
                        where);
                r.gate.release(100);
                deadline = System.nanoTime() + TimeUnit.SECONDS.toNanos(10);
                while ((p.uploading() || r.sent.size() < 2 * n) && System.nanoTime() < deadline) {
                    Thread.sleep(2);
                }
                assertBurstsWentWhole(plan, frames.subList(0, 2 * n), r);
            } finally {
                network.shutdownNow();
            }
        }
    }

    @Test
    void withoutAPanelThePoseFrameGoesWholeAndItsIdFramesStayHome() throws Exception {
        CapturePlan plan = plan(4);
        List<Frame> frames = new ArrayList<>();
        long t = 5_000_000_000L;
        frames.add(new Frame(result(plan, "pose", t), panelAt(0, 0, 12)));
        for (int i = 1; i <= plan.idFramesPerBurst; i++) {
            frames.add(new Frame(result(plan, "id", t + i * FRAME_NS), panelAt(0, 0, 12)));
        }
        for (int lag : new int[] {0, -1}) {
            Recorder r = new Recorder(null);
            FramePipeline p = pipeline(plan, r, DIRECT);
            feed(p, frames, lag);
            assertEquals(1, r.sent.size());
            assertNull(r.sent.get(0).crop, "the whole plane: the server says why");
            assertEquals(W * H, r.bodies.get(0).length);
            assertEquals(Collections.singletonMap(FramePipeline.DROP_NO_PANEL_FOR_ID,
                    (long) plan.idFramesPerBurst), p.dropCounts());
        }
    }

    @Test
    void anIdFrameTheDescriberRefusesLeavesItsBurstToGoWithoutIt() throws Exception {
        CapturePlan plan = plan(4);
        List<Frame> frames = bursts(plan, 1);
        Frame bad = frames.get(2);
        frames.set(2, new Frame(bad.result.toBuilder().exposureNs(TRANSITION_EXPOSURE_NS).build(), bad.packed));
        Recorder r = new Recorder(null);
        FramePipeline p = pipeline(plan, r, DIRECT);
        feed(p, frames, 0);
        assertEquals(frames.size() - 1, r.sent.size(), "sent as soon as its last ID frame came: " + r.heard);
        Map<String, Long> drops = p.dropCounts();
        assertEquals(1, drops.size());
        assertTrue(drops.keySet().iterator().next().contains("match neither"), drops.toString());
    }

    /**
     * The reviewer's case (issue 12 item 3): a phone without per-frame control, its settings L
     * frames behind its requests. Every frame tagged pose has the ID exposure and the real pose
     * frame is tagged id; by their tags no pose frame would ever go. By their results the bursts
     * go whole when each result comes no later than its image; only the frames still taken with
     * the camera's earlier settings stay home.
     */
    @Test
    void withSettingsLagTheBurstsGoByWhatTheResultsShow() throws Exception {
        CapturePlan plan = plan(4);
        for (int lag : new int[] {1, 2}) {
            for (int order : new int[] {0, 1, 3}) {
                List<Frame> exposed = bursts(plan, 3);
                List<Frame> delivered = withSettingsLag(plan, exposed, lag);
                assertEquals("id", delivered.get(lag).result.request, "the pose frame is tagged id");
                Recorder r = new Recorder(null);
                FramePipeline p = pipeline(lagging(), plan, r, DIRECT);
                feed(p, delivered, order);
                String where = "lag " + lag + ", order " + order;
                assertBurstsWentWhole(plan, exposed, r);
                assertEquals(3, r.heard.stream().filter(h -> h.startsWith("pose")).count(), where);
                Map<String, Long> drops = p.dropCounts();
                assertEquals(lag, drops.values().stream().mapToLong(Long::longValue).sum(), where + ": " + drops);
                assertTrue(drops.keySet().stream().allMatch(d -> d.contains("settings in transition")), where);
                List<String> lagWarnings = p.warnings().stream().filter(w -> w.contains("SYNC_MAX_LATENCY unknown"))
                        .collect(java.util.stream.Collectors.toList());
                assertEquals(1, lagWarnings.size(), where + ": said once: " + p.warnings());
            }
        }
    }

    /**
     * When images come before their results, the pipeline guesses an image's kind from its place
     * after the last pose frame. A lag moves the tags, not the exposures, so the guess holds; a
     * frame of the settings' transition at the start may cost the first burst, never a later one.
     */
    @Test
    void withSettingsLagImagesBeforeTheirResultsStillFormBursts() throws Exception {
        CapturePlan plan = plan(4);
        int n = plan.idFramesPerBurst + 1;
        Random rng = new Random(7);
        for (int lag : new int[] {1, 2}) {
            List<List<Frame>> exposedRuns = new ArrayList<>();
            List<Recorder> recorders = new ArrayList<>();
            for (int order : new int[] {-1, -2, -3}) {
                List<Frame> exposed = bursts(plan, 4);
                Recorder r = new Recorder(null);
                feed(pipeline(lagging(), plan, r, DIRECT), withSettingsLag(plan, exposed, lag), order);
                exposedRuns.add(exposed);
                recorders.add(r);
            }
            for (int trial = 0; trial < 10; trial++) {
                List<Frame> exposed = bursts(plan, 4);
                List<Frame> delivered = withSettingsLag(plan, exposed, lag);
                Recorder r = new Recorder(null);
                FramePipeline p = pipeline(lagging(), plan, r, DIRECT);
                int results = 0;
                int images = 0;
                while (results < delivered.size() || images < delivered.size()) {
                    boolean result = images == delivered.size() || (results < delivered.size()
                            && results - images < 3 && (images - results >= 3 || rng.nextBoolean()));
                    if (result) {
                        p.onResult(delivered.get(results++).result);
                    } else {
                        delivered.get(images++).image(p);
                    }
                }
                exposedRuns.add(exposed);
                recorders.add(r);
            }
            for (int run = 0; run < recorders.size(); run++) {
                List<Frame> exposed = exposedRuns.get(run);
                Recorder r = recorders.get(run);
                assertTrue(r.sent.size() >= 3 * n, "lag " + lag + ", run " + run + ": " + r.heard);
                assertBurstsWentWhole(plan, exposed.subList(n, exposed.size()), tail(r, 3 * n));
            }
        }
    }

    /** The last {@code frames} uploads, as a recorder of their own. */
    private static Recorder tail(Recorder r, int frames) {
        Recorder out = new Recorder(null);
        out.sent.addAll(r.sent.subList(r.sent.size() - frames, r.sent.size()));
        out.bodies.addAll(r.bodies.subList(r.bodies.size() - frames, r.bodies.size()));
        return out;
    }

    /**
     * Each frame goes with the gyroscope's mean rate over its own readout (SENSOR_TIMESTAMP to the
     * last row's exposure end), turned into the camera frame; not with the readings between frames.
     */
    @Test
    void eachFrameGoesWithTheMeanRateOverItsReadout() throws Exception {
        CapturePlan plan = plan(1);
        List<Frame> frames = bursts(plan, 3);
        Recorder r = new Recorder(null);
        GyroHistory rates = new GyroHistory();
        for (int k = 0; k < frames.size(); k++) {
            FrameResult result = frames.get(k).result;
            long t = result.timestampNs;
            long end = t + result.rollingShutterSkewNs + result.exposureNs;
            assertTrue(end + 1_000_000L < t + FRAME_NS, "the fixture leaves a gap between readouts");
            // About the device's z axis: 0.1 (k + 1) and 0.3 (k + 1) rad/s, a mean of 0.2 (k + 1).
            rates.add(t, new float[] {0, 0, 0.1f * (k + 1)});
            rates.add(end, new float[] {0, 0, 0.3f * (k + 1)});
            rates.add(end + 1_000_000L, new float[] {5, 5, 5}); // between readouts: nobody's
        }
        FramePipeline p = FramePipeline.forCamera(Devices.load(Devices.LOGICAL), plan, null, new GravityHistory(),
                rates, r, DIRECT, r);
        feed(p, frames, 0);
        assertEquals(3, r.sent.size());
        for (FrameMeta m : r.sent) {
            int k = (int) ((m.timestampNs - frames.get(0).t()) / FRAME_NS);
            JSONArray rate = m.toJson().getJSONArray("angular_velocity_camera_dps");
            // The back camera at 90 deg looks along the device's -z: the same turn about its own z reads negative.
            assertEquals(0, rate.getDouble(0), 1e-9);
            assertEquals(0, rate.getDouble(1), 1e-9);
            assertEquals(-Math.toDegrees(0.2 * (k + 1)), rate.getDouble(2), 1e-4, "frame " + k);
        }
        assertFalse(p.warnings().contains(FramePipeline.NO_RATE_UNKNOWN_TIMESTAMPS));

        // Timestamps on the camera's own clock: no rate at all rather than a wrong one, said once.
        Recorder unknown = new Recorder(null);
        CameraFacts ownClock = Devices.load(Devices.LOGICAL).toBuilder().timestampSource("unknown").build();
        FramePipeline q = FramePipeline.forCamera(ownClock, plan, null, new GravityHistory(), rates, unknown, DIRECT,
                unknown);
        feed(q, frames, 0);
        assertEquals(3, unknown.sent.size());
        for (FrameMeta m : unknown.sent) {
            assertNull(m.angularVelocityCameraDps());
        }
        assertEquals(1, q.warnings().stream().filter(FramePipeline.NO_RATE_UNKNOWN_TIMESTAMPS::equals).count());
    }

    @Test
    void halvesThatNeverMeetAreDroppedAndMemoryStaysBounded() throws Exception {
        CapturePlan plan = plan(4);
        List<Frame> frames = bursts(plan, 20);
        Recorder r = new Recorder(null);
        FramePipeline p = pipeline(plan, r, DIRECT);
        for (Frame f : frames) {
            p.onResult(f.result); // the image reader lost every image
        }
        long kept = plan.idFramesPerBurst + 3;
        assertEquals(Collections.singletonMap(FramePipeline.DROP_NO_IMAGE, frames.size() - kept), p.dropCounts());
        p.close();
        assertEquals(kept, p.dropCounts().get(FramePipeline.DROP_CLOSED).longValue());
        frames.get(0).image(p);
        p.onResult(frames.get(0).result);
        assertTrue(r.sent.isEmpty(), "nothing after close");
    }

    @Test
    void theDescribersWarningsAreKeptOnceEach() throws Exception {
        CapturePlan plan = plan(1);
        assertTrue(plan.pose.oisOff, "the fixture can switch stabilisation off");
        List<Frame> frames = new ArrayList<>();
        for (Frame f : bursts(plan, 3)) {
            frames.add(new Frame(f.result.toBuilder().oisMode("on").build(), f.packed));
        }
        Recorder r = new Recorder(null);
        FramePipeline p = pipeline(plan, r, DIRECT);
        feed(p, frames, 0);
        assertEquals(3, r.sent.size());
        List<String> warnings = p.warnings();
        assertEquals(1, warnings.stream().filter(w -> w.contains("stabilisation")).count(), warnings.toString());
        assertEquals(warnings.size(), new java.util.HashSet<>(warnings).size(), "each once");
    }
}
