package io.lumipose.client.flow;

import static org.junit.jupiter.api.Assertions.assertArrayEquals;
import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertFalse;
import static org.junit.jupiter.api.Assertions.assertNull;
import static org.junit.jupiter.api.Assertions.assertTrue;

import java.nio.ByteBuffer;
import java.util.ArrayList;
import java.util.List;

import org.junit.jupiter.api.Test;

import io.lumipose.client.camera.CameraFacts;
import io.lumipose.client.camera.Devices;
import io.lumipose.client.camera.FrameResult;
import io.lumipose.client.capture.CaptureOptions;
import io.lumipose.client.capture.CapturePlan;
import io.lumipose.client.capture.FrameDescriber;
import io.lumipose.client.frame.FrameMeta;
import io.lumipose.client.frame.GreyPreview;
import io.lumipose.client.sensor.GravityHistory;
import io.lumipose.client.sensor.GyroHistory;

/** The shutter: nothing kept until armed, then the next kept pose frame whole, in either arrival order. */
class StillCaptureTest {
    private final CameraFacts facts = Devices.load(Devices.FRONT_270);
    private final CapturePlan plan;
    private final List<FrameMeta> photos = new ArrayList<>();
    private final List<byte[]> pixels = new ArrayList<>();
    private final List<String> drops = new ArrayList<>();
    private final List<GreyPreview> previews = new ArrayList<>();
    private final GravityHistory attitude = new GravityHistory();
    private final StillCapture shutter;

    StillCaptureTest() throws Exception {
        plan = CapturePlan.plan(facts, new CaptureOptions(8_400_000L, 0, 1, 2.0, 3_200_000L))
                .forStills(facts, 20_000_000L, 800);
        shutter = new StillCapture(new FrameDescriber(facts, plan, null), attitude, new GyroHistory(), true,
                Runnable::run, new StillCapture.Listener() {
                    @Override
                    public void onPhoto(byte[] luma, FrameMeta meta) {
                        pixels.add(luma);
                        photos.add(meta);
                    }

                    @Override
                    public void onPreview(GreyPreview preview) {
                        previews.add(preview);
                    }

                    @Override
                    public void onDropped(String reason) {
                        drops.add(reason);
                    }
                }, 100_000_000L);
    }

    private FrameResult result(long t) {
        return FrameResult.builder(t).exposureNs(plan.pose.exposureNs).sensitivityIso(plan.pose.sensitivityIso)
                .build();
    }

    /** A plane with rows padded to 64 bytes, every sample the frame's number. */
    private ByteBuffer plane(int value) {
        int w = plan.output.width;
        int stride = (w + 63) / 64 * 64;
        byte[] b = new byte[(plan.output.height - 1) * stride + w];
        java.util.Arrays.fill(b, (byte) value);
        return ByteBuffer.wrap(b);
    }

    private void image(long t, int value) {
        shutter.onImage(t, plane(value), plan.output.width, plan.output.height, (plan.output.width + 63) / 64 * 64, 1);
    }

    @Test
    void theBoardsPlanKeepsThePositioningGeometry() throws Exception {
        CapturePlan positioning = CapturePlan.plan(facts, new CaptureOptions(8_400_000L, 0, 1, 2.0, 3_200_000L));
        assertEquals(positioning.output, plan.output);
        assertEquals(positioning.pose.cropRegion, plan.pose.cropRegion);
        assertEquals(positioning.pose.focusDiopters, plan.pose.focusDiopters);
        assertEquals(20_000_000L, plan.pose.exposureNs);
        assertEquals(Math.max(facts.sensitivityMin, Math.min(facts.sensitivityMax, 800)),
                (int) plan.pose.sensitivityIso);
        assertNull(plan.id);
        CapturePlan loud = positioning.forStills(facts, 20_000_000L, 10_000_000);
        assertEquals(facts.sensitivityMax, loud.pose.sensitivityIso, "clamped to the camera's range");
        assertTrue(loud.notes.contains("ISO 10000000 clamped to " + facts.sensitivityMax), loud.notes.toString());
    }

    @Test
    void nothingIsTakenUntilArmedThenTheNextFrameWhole() {
        image(1_000_000L, 1);
        shutter.onResult(result(1_000_000L));
        assertTrue(photos.isEmpty());
        assertEquals(1, previews.size());
        assertTrue(shutter.arm());
        assertFalse(shutter.arm(), "one shot at a time");
        image(50_000_000L, 2); // within 100 ms of the last preview: none
        shutter.onResult(result(50_000_000L));
        assertEquals(1, previews.size());
        assertEquals(1, photos.size());
        FrameMeta m = photos.get(0);
        assertNull(m.crop, "whole");
        assertEquals(plan.output.width, m.width);
        assertEquals(plan.output.width, m.rowStride, "packed");
        assertEquals(0.02, m.exposureS, 1e-12);
        assertEquals(plan.output.width * plan.output.height, pixels.get(0).length);
        assertEquals(2, pixels.get(0)[pixels.get(0).length - 1]);
        assertFalse(shutter.armed());
        image(300_000_000L, 3);
        shutter.onResult(result(300_000_000L));
        assertEquals(1, photos.size(), "disarmed after its photo");
        assertEquals(2, previews.size());
    }

    @Test
    void aResultFirstAndAFrameTheDescriberDropsWaitForTheNext() {
        shutter.arm();
        shutter.onResult(FrameResult.builder(10L).exposureNs(1_000_000L).sensitivityIso(100).build());
        image(10L, 4);
        assertEquals(1, drops.size(), "settings in transition");
        assertTrue(photos.isEmpty());
        shutter.onResult(result(20L));
        image(20L, 5);
        assertEquals(1, photos.size());
        assertArrayEquals(new byte[] {5, 5}, java.util.Arrays.copyOf(pixels.get(0), 2));
    }

    @Test
    void closedTakesNothing() {
        shutter.arm();
        shutter.close();
        image(10L, 4);
        shutter.onResult(result(10L));
        assertTrue(photos.isEmpty());
        assertFalse(shutter.arm());
    }
}
