package io.lumipose.client.replay;

import static org.junit.jupiter.api.Assertions.assertArrayEquals;
import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertNotNull;
import static org.junit.jupiter.api.Assertions.assertNull;
import static org.junit.jupiter.api.Assertions.assertThrows;
import static org.junit.jupiter.api.Assertions.assertTrue;

import java.io.File;
import java.io.IOException;
import java.nio.ByteBuffer;
import java.nio.charset.StandardCharsets;
import java.nio.file.Files;
import java.nio.file.Path;
import java.util.ArrayList;
import java.util.HashMap;
import java.util.List;
import java.util.Map;
import java.util.concurrent.Executor;

import org.json.JSONArray;
import org.json.JSONObject;
import org.junit.jupiter.api.Test;
import org.junit.jupiter.api.io.TempDir;

import io.lumipose.client.camera.CameraFacts;
import io.lumipose.client.camera.FrameResult;
import io.lumipose.client.camera.PixelSize;
import io.lumipose.client.capture.CapturePlan;
import io.lumipose.client.flow.FramePipeline;
import io.lumipose.client.flow.FrameSink;
import io.lumipose.client.frame.FrameMeta;
import io.lumipose.client.frame.LumaPlane;
import io.lumipose.client.net.FrameUploader;
import io.lumipose.client.net.LocateResult;
import io.lumipose.client.sensor.GravityHistory;
import io.lumipose.client.sensor.GravityTransform;
import io.lumipose.client.sensor.GyroHistory;
import io.lumipose.client.sensor.GyroTransform;
import io.lumipose.client.sensor.LensFacing;

class ReplayCameraTest {
    private static final int W = 40;
    private static final int H = 30;
    /** The renderer's camera: 3.52 mm lens, 9 um pixels (the Mi 8 front's at a tenth of its size). */
    private static final double PIXEL_M = 9e-6;
    private static final double FOCAL_M = 3.52e-3;
    private static final double FX = FOCAL_M / PIXEL_M;

    @TempDir
    Path dir;

    /** A fixture as `lumipose simulate` writes it; frame i's pixel (x, y) is i + x + 2 y. */
    private void writeFrame(int i, String kind, int fileStride, double[] gravity) throws IOException {
        JSONObject camera = new JSONObject().put("fx", FX).put("fy", FX).put("cx", (W - 1) / 2.0)
                .put("cy", (H - 1) / 2.0).put("distortion", new JSONArray()).put("pixel_size_m", PIXEL_M)
                .put("focal_length_m", FOCAL_M);
        JSONObject o = new JSONObject().put("schema", "lumipose.frame/1").put("format", "Y8").put("width", W)
                .put("height", H).put("row_stride", fileStride).put("camera", camera)
                .put("exposure_s", "id".equals(kind) ? 1.25e-4 : 0.001)
                // the ID frames' ISO keeps a fifth of the pose frame's brightness, as the plan asks
                .put("iso", "id".equals(kind) ? 640.0 : 400.0)
                .put("rolling_shutter_skew_s", 0.03).put("timestamp_ns", 1000000000L + i * 33333333L)
                .put("gravity_camera", new JSONArray(gravity)).put("frame_kind", kind)
                .put("angular_velocity_camera_dps", new JSONArray(rateDps(i)))
                .put("ground_truth", new JSONObject().put("position_m", new JSONArray(new double[] {0.1 * i, 0, 1.3}))
                        .put("rotation_wc", new JSONArray("[[1,0,0],[0,1,0],[0,0,1]]")));
        String stem = String.format("walk_%04d", i);
        Files.write(dir.resolve(stem + ".json"), o.toString(2).getBytes(StandardCharsets.UTF_8));
        byte[] y = new byte[fileStride * H];
        for (int r = 0; r < H; r++) {
            for (int c = 0; c < W; c++) {
                y[r * fileStride + c] = (byte) (i + c + 2 * r);
            }
        }
        Files.write(dir.resolve(stem + ".y"), y);
    }

    /** Frame i's rotation rate in the fixture, camera frame, deg/s. */
    private static double[] rateDps(int i) {
        return new double[] {0.5 * i, -1.0, 2.0};
    }

    private Recording recording(int frames) throws IOException {
        for (int i = 0; i < frames; i++) {
            double[] gravity = {0.01 * i, -0.02, -1};
            writeFrame(i, i % 5 == 0 ? "pose" : "id", i % 2 == 0 ? W : W + 3, gravity);
        }
        Files.write(dir.resolve("scene.json"), "{}".getBytes(StandardCharsets.UTF_8));
        return Recording.open(dir.toFile());
    }

    @Test
    void readsFixturesInNameOrderWithoutTheirFilePadding() throws IOException {
        Recording r = recording(7);
        assertEquals(7, r.frames().size());
        RecordedFrame third = r.frames().get(3);
        assertEquals("walk_0003", third.name);
        assertEquals("id", third.kind);
        assertEquals(1000000000L + 3 * 33333333L, third.timestampNs);
        byte[] luma = third.luma();
        assertEquals(W * H, luma.length);
        assertEquals((byte) (3 + 7 + 2 * 11), luma[11 * W + 7]);
        assertArrayEquals(new double[] {0.3, 0, 1.3}, third.truthPositionM(), 1e-12);
    }

    @Test
    void characteristicsDescribeExactlyTheRenderedCamera() throws IOException {
        JSONObject facts = new SimulatedPhone(recording(2).frames()).characteristics();
        assertEquals("[0,0,40,30]", facts.getJSONArray("active_array").toString());
        assertEquals("[0,0,40,30]", facts.getJSONArray("pre_correction_active_array").toString());
        assertEquals("[40,30]", facts.getJSONArray("pixel_array").toString());
        // 40 px of 9 um = 0.36 mm; fx = 3.52 mm / 9 um = 391.1 px; Camera2's centre of a 40 px row is 20.
        JSONArray size = facts.getJSONArray("physical_size_mm");
        assertEquals(0.36, size.getDouble(0), 1e-6);
        assertEquals(0.27, size.getDouble(1), 1e-6);
        assertEquals(3.52, facts.getJSONArray("available_focal_lengths_mm").getDouble(0), 1e-6);
        JSONArray k = facts.getJSONArray("lens_intrinsic_calibration");
        assertEquals(391.111, k.getDouble(0), 1e-3);
        assertEquals(391.111, k.getDouble(1), 1e-3);
        assertEquals(20.0, k.getDouble(2), 0);
        assertEquals(15.0, k.getDouble(3), 0);
        assertEquals(0.0, k.getDouble(4), 0);
        assertEquals(270, facts.getInt("sensor_orientation"));
        assertEquals("front", facts.getString("lens_facing"));
        assertEquals("[[40,30,33333333]]", facts.getJSONArray("yuv_outputs").toString());
    }

    @Test
    void thePlanForThisPhoneAsksForTheRecordedFrames() throws Exception {
        ReplayCamera camera = new ReplayCamera(recording(6));
        CapturePlan plan = CapturePlan.plan(camera.facts(), camera.captureOptions(2, 2.0));
        assertEquals(new PixelSize(W, H), plan.output);
        assertEquals(1000000L, plan.pose.exposureNs);
        assertEquals(400, plan.pose.sensitivityIso.intValue());
        assertEquals(125000L, plan.id.exposureNs);
        assertEquals(640, plan.id.sensitivityIso.intValue());
        // One beacon: no ID frames asked for.
        assertNull(CapturePlan.plan(camera.facts(), camera.captureOptions(1, 2.0)).id);
    }

    @Test
    void eachResultSaysWhatTheFrameWasTakenWith() throws Exception {
        Recording r = recording(2);
        ReplayCamera camera = new ReplayCamera(r);
        CapturePlan plan = CapturePlan.plan(camera.facts(), camera.captureOptions(2, 2.0));
        JSONObject result = camera.phone().result(r.frames().get(1), plan.id);
        assertEquals(1033333333L, result.getLong("sensor_timestamp_ns"));
        assertEquals("id", result.getString("request"));
        assertEquals(125000L, result.getLong("sensor_exposure_time_ns"));
        assertEquals(640, result.getInt("sensor_sensitivity"));
        assertEquals(plan.id.frameDurationNs, result.getLong("sensor_frame_duration_ns"));
        assertEquals("contrast_curve", result.getString("tonemap_mode"));
        assertEquals(30000000L, result.getLong("sensor_rolling_shutter_skew_ns"));
        assertEquals("[0,0,40,30]", result.getJSONArray("scaler_crop_region").toString());
        assertEquals(3.52, result.getDouble("lens_focal_length_mm"), 1e-6);
    }

    @Test
    void aCameraThatIsNotTheRecordingsIsRefused() throws IOException {
        writeFrame(0, "pose", W, new double[] {0, 0, -1});
        String text = new String(Files.readAllBytes(dir.resolve("walk_0000.json")), StandardCharsets.UTF_8);
        // The same frame whose principal point is 3 px off the centre the facts would give.
        Files.write(dir.resolve("walk_0001.json"), text.replace("\"cx\": 19.5", "\"cx\": 22.5")
                .getBytes(StandardCharsets.UTF_8));
        Files.copy(dir.resolve("walk_0000.y"), dir.resolve("walk_0001.y"));
        Recording r = Recording.open(dir.toFile());
        assertThrows(IllegalArgumentException.class, () -> new SimulatedPhone(r.frames()));
    }

    /** What a sink sees, and proof it must copy: the buffer is written over after each call. */
    private static final class Capture implements FrameSink {
        final List<String> calls = new ArrayList<String>();
        final Map<Long, byte[]> images = new HashMap<Long, byte[]>();
        final List<FrameResult> results = new ArrayList<FrameResult>();
        ByteBuffer kept;

        @Override
        public void onResult(FrameResult result) {
            results.add(result);
            calls.add("result");
        }

        @Override
        public void onImage(long timestampNs, ByteBuffer yPlane, int width, int height, int rowStride,
                            int pixelStride) {
            assertTrue(rowStride > width, "row stride " + rowStride + " for width " + width);
            assertEquals(1, pixelStride);
            assertEquals((long) rowStride * (height - 1) + width, yPlane.remaining(), "no padding after the last row");
            images.put(timestampNs, LumaPlane.copy(yPlane, width, height, rowStride, pixelStride));
            kept = yPlane;
            calls.add("image " + timestampNs);
        }
    }

    @Test
    void playsEveryImageAndResultOnceWithGravityFirst() throws Exception {
        Recording r = recording(12);
        ReplayCamera camera = new ReplayCamera(r);
        CapturePlan plan = CapturePlan.plan(camera.facts(), camera.captureOptions(2, 2.0));
        Capture sink = new Capture();
        GravityHistory gravity = new GravityHistory();
        GyroHistory rates = new GyroHistory();
        final List<String> deliveries = new ArrayList<String>();
        camera.play(plan, sink, gravity, rates, new ReplayCamera.Pace() {
            @Override
            public void beforeDelivery(RecordedFrame frame) {
                deliveries.add(frame.name);
            }
        });
        assertEquals(24, deliveries.size());
        assertEquals(sink.calls.size(), deliveries.size());
        assertEquals(12, sink.results.size());
        assertEquals(12, sink.images.size());
        for (RecordedFrame f : r.frames()) {
            assertArrayEquals(f.luma(), sink.images.get(f.timestampNs), f.name);
            double[] back = GravityTransform.deviceToCamera(gravity.gravityAt(f.timestampNs),
                    SimulatedPhone.SENSOR_ORIENTATION_DEG, LensFacing.FRONT);
            double[] g = f.gravityCamera();
            double norm = Math.sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
            assertArrayEquals(new double[] {g[0] / norm, g[1] / norm, g[2] / norm}, back, 1e-6, f.name);
            // The frame's rate over its readout (30 ms skew and the exposure) is the fixture's own.
            long readoutEnd = f.timestampNs + Math.round((f.rollingShutterSkewS + f.exposureS) * 1e9);
            assertArrayEquals(f.angularVelocityCameraDps(), GyroTransform.deviceToCameraDps(
                    rates.meanOver(f.timestampNs, readoutEnd), SimulatedPhone.SENSOR_ORIENTATION_DEG,
                    LensFacing.FRONT), 1e-4, f.name);
        }
        for (FrameResult result : sink.results) {
            long index = (result.timestampNs - 1000000000L) / 33333333L;
            assertEquals(index % 5 == 0 ? "pose" : "id", result.request);
        }
        assertNotNull(sink.kept);
        assertEquals(ReplayCamera.REUSED, sink.kept.get(0), "the camera reuses its buffer");

        // Without ID frames in the plan, the camera takes none.
        Capture poseOnly = new Capture();
        camera.play(CapturePlan.plan(camera.facts(), camera.captureOptions(1, 2.0)), poseOnly, gravity, rates,
                new ReplayCamera.Pace() {
                    @Override
                    public void beforeDelivery(RecordedFrame frame) {
                    }
                });
        assertEquals(3, poseOnly.images.size());
    }

    /**
     * A phone without per-frame control: each result reports the settings its pixels were taken
     * with (the request {@code lag} frames earlier) and the tag of the request submitted for it.
     * Classified by their results, the pose frames still go, each starting its burst.
     */
    @Test
    void aLaggingPhoneTagsEachFrameWithTheRequestSubmittedForIt() throws Exception {
        Recording r = recording(15);
        for (int lag : new int[] {1, 2}) {
            ReplayCamera camera = new ReplayCamera(r, 12, lag);
            assertEquals(CameraFacts.SYNC_UNKNOWN, camera.facts().syncMaxLatency);
            CapturePlan plan = CapturePlan.plan(camera.facts(), camera.captureOptions(2, 2.0));
            Capture sink = new Capture();
            camera.play(plan, sink, new GravityHistory(), new GyroHistory(), NO_PACE);
            for (FrameResult result : sink.results) {
                long index = (result.timestampNs - 1000000000L) / 33333333L;
                assertEquals(index % 5 == 0 ? 1000000L : 125000L, result.exposureNs.longValue(), "what its pixels show");
                assertEquals((index + lag) % 5 == 0 ? "pose" : "id", result.request, "the request submitted for it");
            }

            final List<FrameMeta> sent = new ArrayList<FrameMeta>();
            GyroHistory rates = new GyroHistory();
            FramePipeline pipeline = FramePipeline.forCamera(camera.facts(), plan, null, new GravityHistory(),
                    rates, new FrameUploader() {
                        @Override
                        public LocateResult upload(byte[] luma, FrameMeta meta) {
                            sent.add(meta);
                            return LocateResult.fromJson("{\"schema\": \"lumipose.result/1\", \"ok\": false, "
                                    + "\"reason\": \"no_beacon\"}");
                        }
                    }, DIRECT, IGNORE);
            camera.play(plan, pipeline, new GravityHistory(), rates, NO_PACE);
            List<Long> poses = new ArrayList<Long>();
            for (FrameMeta m : sent) {
                int index = (int) ((m.timestampNs - 1000000000L) / 33333333L);
                if ("pose".equals(m.frameKind)) {
                    poses.add((long) index);
                }
                // The replayed gyroscope's rate reaches the sent JSON, turned back into the camera frame.
                JSONArray rate = m.toJson().getJSONArray("angular_velocity_camera_dps");
                for (int k = 0; k < 3; k++) {
                    assertEquals(rateDps(index)[k], rate.getDouble(k), 1e-4, m.timestampNs + "[" + k + "]");
                }
            }
            assertEquals(java.util.Arrays.asList(0L, 5L, 10L), poses, "lag " + lag + ": " + pipeline.dropCounts());
            assertEquals(3, pipeline.burstsSubmitted());
            for (String reason : pipeline.dropCounts().keySet()) {
                assertEquals(FramePipeline.DROP_NO_PANEL_FOR_ID, reason, "the fixtures show no panel, nothing else");
            }
        }
    }

    private static final ReplayCamera.Pace NO_PACE = new ReplayCamera.Pace() {
        @Override
        public void beforeDelivery(RecordedFrame frame) {
        }
    };

    private static final Executor DIRECT = new Executor() {
        @Override
        public void execute(Runnable command) {
            command.run();
        }
    };

    private static final FramePipeline.Listener IGNORE = new FramePipeline.Listener() {
        @Override
        public void onPoseResult(FrameMeta meta, LocateResult result) {
        }

        @Override
        public void onIdResult(FrameMeta meta, LocateResult result) {
        }

        @Override
        public void onDropped(String reason) {
        }

        @Override
        public void onFailure(FrameMeta meta, Exception error) {
        }
    };

    @Test
    void deliveryOrderMixesImageFirstAndLateResultsAsCamera2Allows() throws IOException {
        Recording r = recording(24);
        List<ReplayCamera.Event> events = new ReplayCamera(r).events(r.frames());
        assertEquals(48, events.size());
        Map<RecordedFrame, Integer> imageAt = new HashMap<RecordedFrame, Integer>();
        Map<RecordedFrame, Integer> resultAt = new HashMap<RecordedFrame, Integer>();
        for (int i = 0; i < events.size(); i++) {
            (events.get(i).image ? imageAt : resultAt).put(events.get(i).frame, i);
        }
        List<RecordedFrame> frames = r.frames();
        int imageFirst = 0;
        int resultAfterNextImage = 0;
        for (int i = 0; i < frames.size(); i++) {
            RecordedFrame f = frames.get(i);
            if (imageAt.get(f) < resultAt.get(f)) {
                imageFirst++;
            }
            if (i + 1 < frames.size() && resultAt.get(f) > imageAt.get(frames.get(i + 1))) {
                resultAfterNextImage++;
            }
            if (i > 0) {
                // Camera2 keeps each stream in capture order.
                assertTrue(imageAt.get(f) > imageAt.get(frames.get(i - 1)));
                assertTrue(resultAt.get(f) > resultAt.get(frames.get(i - 1)));
            }
            assertTrue(events.get(Math.min(imageAt.get(f), resultAt.get(f))).first);
        }
        assertTrue(imageFirst > 0 && imageFirst < frames.size(), imageFirst + " of 24 image first");
        assertTrue(resultAfterNextImage > 0, "no result came after the next frame's image");
    }
}
