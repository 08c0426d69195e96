package io.lumipose.client.capture;

import static org.junit.jupiter.api.Assertions.assertArrayEquals;
import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertFalse;
import static org.junit.jupiter.api.Assertions.assertNull;
import static org.junit.jupiter.api.Assertions.assertThrows;
import static org.junit.jupiter.api.Assertions.assertTrue;

import java.util.Arrays;

import org.junit.jupiter.api.Test;

import io.lumipose.client.camera.ArrayRect;
import io.lumipose.client.camera.CameraFacts;
import io.lumipose.client.camera.Devices;
import io.lumipose.client.camera.PixelSize;
import io.lumipose.client.protocol.CaptureProtocol;

class CapturePlanTest {
    private static final double PERIOD_NS = IdCapturePlan.messagePeriodNs(); // 21 chips at 2.5 kHz: 8.4 ms

    private static CaptureOptions options(int beacons) {
        return new CaptureOptions(8_400_000L, 125_000L, beacons, 2.0, 3_200_000L);
    }

    /** Issue 12 item 1: a one-beacon map has nothing to tell apart, so no ID frames are taken. */
    @Test
    void noIdFramesForAOneBeaconMap() throws Exception {
        CapturePlan plan = CapturePlan.plan(Devices.load(Devices.LOGICAL), options(1));
        assertNull(plan.id);
        assertEquals(0, plan.idFramesPerBurst);
        assertEquals(Arrays.asList(plan.pose), plan.burst());
        assertTrue(plan.notes.contains("one beacon in the map: no ID frames"), plan.notes.toString());
        assertNull(CapturePlan.plan(Devices.load(Devices.LOGICAL),
                new CaptureOptions(8_400_000L, 0, 4, 2.0, 3_200_000L)).id, "ID exposure 0: no ID frames");
    }

    /**
     * Issue 12 item 2: ID frames start a quarter message apart, and the whole cycle (pose + 4 ID
     * frames) is a whole number of messages plus the golden step 0.382, so successive bursts see the
     * message at evenly spread phases. Logical camera at 2000x1500, stream minimum 16.67 ms, at no
     * rate limit to speak of: ID frame = 2.25 messages = 18.9 ms; cycle >= 16.67 + 4 * 18.9 =
     * 92.27 ms -> 11.382 messages = 95.61 ms; the last ID frame takes the rest, 22.24 ms (the pose
     * frame took it before issue 26). At the live rate: CapturePlanRateTest.
     */
    @Test
    void theBurstStepsTheMessagePhase() throws Exception {
        CapturePlan plan = CapturePlan.plan(Devices.load(Devices.LOGICAL), options(4)).atBurstsPerSecond(1000);
        assertEquals(4, plan.idFramesPerBurst);
        assertEquals(5, plan.burst().size());
        assertEquals(18_900_000L, plan.id.frameDurationNs);
        assertEquals(0.25, fraction(plan.id.frameDurationNs), 1e-6);
        assertEquals(CaptureProtocol.GOLDEN_STEP, fraction(plan.burstIntervalNs), 1e-6);
        assertEquals(11.0 + CaptureProtocol.GOLDEN_STEP, plan.burstIntervalNs / PERIOD_NS, 1e-6);
        long sum = 0;
        for (RequestSpec spec : plan.burst()) {
            sum += spec.frameDurationNs;
        }
        assertEquals(plan.burstIntervalNs, sum);
        assertEquals(16_666_666L, plan.pose.frameDurationNs);
        assertEquals(plan.burstIntervalNs - 16_666_666L - 3 * 18_900_000L, plan.burst().get(4).frameDurationNs);
        // The ID frames keep the pose frames' geometry; only exposure, ISO and timing differ.
        assertEquals(plan.pose.cropRegion, plan.id.cropRegion);
        assertEquals(125_000L, plan.id.exposureNs);
        assertEquals(Integer.valueOf(672), plan.id.sensitivityIso); // 50 x (8.4 ms / 0.125 ms) x 0.2
    }

    @Test
    void asksForTheSettingsThatKeepEdgesWhereTheServerFitsThem() throws Exception {
        CapturePlan plan = CapturePlan.plan(Devices.load(Devices.LOGICAL), options(1));
        RequestSpec pose = plan.pose;
        assertEquals(new PixelSize(2000, 1500), plan.output);
        assertEquals(new ArrayRect(0, 0, 4000, 3000), pose.cropRegion);
        assertTrue(pose.oisOff);
        assertArrayEquals(new float[] {0, 0, 1, 1}, pose.toneCurve(), 0f);
        assertFalse(pose.srgbPreset, "the contrast curve where there is one");
        assertTrue(pose.rotateAndCropNone);
        assertTrue(pose.edgeOff);
        assertTrue(pose.noiseReductionOff);
        assertTrue(pose.distortionCorrectionOff);
        assertEquals(0.5f, pose.focusDiopters, 1e-6f); // ceiling 2 m away
        assertEquals(8_400_000L, pose.exposureNs);
        assertEquals(Integer.valueOf(50), pose.sensitivityIso);
        assertEquals(Arrays.asList("one beacon in the map: no ID frames"), plan.notes);
    }

    /** Correction off: the crop region is the pre-correction array's, all of it. */
    @Test
    void withCorrectionOffTheCropIsThePreCorrectionArray() throws Exception {
        CapturePlan plan = CapturePlan.plan(Devices.load(Devices.PRE_CORRECTION), options(1));
        assertEquals(new ArrayRect(0, 0, 4080, 3060), plan.pose.cropRegion);
        assertEquals(new PixelSize(2040, 1530), plan.output);
        assertFalse(plan.pose.rotateAndCropNone, "no such key before API 30");
        assertTrue(plan.notes.contains("focus distance uncalibrated: the ceiling may be out of focus"), plan.notes.toString());
    }

    @Test
    void saysWhatTheFrontCameraCannotDo() throws Exception {
        CapturePlan plan = CapturePlan.plan(Devices.load(Devices.FRONT_270),
                new CaptureOptions(8_400_000L, 125_000L, 4, 2.0, 1_300_000L));
        assertNull(plan.pose.toneCurve());
        assertFalse(plan.pose.srgbPreset, "no preset curve on this camera either");
        assertNull(plan.pose.focusDiopters, "fixed focus");
        assertFalse(plan.pose.edgeOff);
        assertEquals(new ArrayRect(0, 0, 5184, 3880), plan.pose.cropRegion);
        assertTrue(plan.notes.contains("no linear tone curve: the server assumes one"), plan.notes.toString());
        assertTrue(plan.notes.stream().anyMatch(n -> n.startsWith("SYNC_MAX_LATENCY unknown, not per-frame control")),
                plan.notes.toString());
    }

    /** Without a contrast curve the sRGB preset: a known curve, which the server undoes (tone_curve "srgb"). */
    @Test
    void withoutAContrastCurveTheSrgbPresetCurve() throws Exception {
        CapturePlan plan = CapturePlan.plan(Devices.load(Devices.PRESET_CURVE_ONLY), options(4));
        for (RequestSpec spec : plan.burst()) {
            assertNull(spec.toneCurve(), spec.kind);
            assertTrue(spec.srgbPreset, spec.kind);
        }
        assertTrue(plan.notes.contains("no linear tone curve: the sRGB preset curve instead, which the server undoes"),
                plan.notes.toString());
        assertFalse(plan.notes.contains("no linear tone curve: the server assumes one"), plan.notes.toString());
        RequestSpec pose = plan.pose;
        assertThrows(IllegalArgumentException.class, () -> new RequestSpec(pose.kind, pose.exposureNs,
                pose.sensitivityIso, pose.frameDurationNs, pose.focusDiopters, pose.cropRegion, pose.oisOff,
                new float[] {0, 0, 1, 1}, true, pose.rotateAndCropNone, pose.edgeOff, pose.noiseReductionOff,
                pose.distortionCorrectionOff));
    }

    /** Issue 12 item 9: without rolling-shutter skew the stripes have no row times: ID capture off, said. */
    @Test
    void withoutRollingShutterSkewTheIdFramesGo() throws Exception {
        CapturePlan plan = CapturePlan.plan(Devices.load(Devices.LOGICAL), options(4));
        CapturePlan poseOnly = plan.withoutIdFrames("no rolling-shutter skew: beacon IDs off");
        assertNull(poseOnly.id);
        assertEquals(1, poseOnly.burst().size());
        assertEquals(100_000_000L, poseOnly.pose.frameDurationNs, "pose frames alone, at the live rate");
        assertTrue(poseOnly.notes.contains("no rolling-shutter skew: beacon IDs off"));
        assertEquals(poseOnly, poseOnly.withoutIdFrames("again"));
    }

    /** A camera whose shortest exposure is longer than a code chip still positions, without beacon IDs. */
    @Test
    void anExposureTooLongForTheCodeLeavesPoseFrames() throws Exception {
        CameraFacts slow = Devices.load(Devices.LOGICAL).toBuilder().exposureTimeRangeNs(1_000_000L, 500_000_000L).build();
        CapturePlan plan = CapturePlan.plan(slow, options(4));
        assertNull(plan.id);
        assertTrue(plan.notes.get(plan.notes.size() - 1).contains("one code chip"), plan.notes.toString());
    }

    @Test
    void theProtocolsExposuresByDefault() throws Exception {
        CaptureOptions o = CaptureOptions.fromProtocol(true, 4, 2.0, 3_200_000L);
        assertEquals(CaptureProtocol.POSE_EXPOSURE_NS, o.poseExposureNs);
        assertEquals(CaptureProtocol.ID_EXPOSURE_NS, o.idExposureNs);
        assertTrue(o.wantsIdFrames());
        assertFalse(CaptureOptions.fromProtocol(true, 1, 2.0, 3_200_000L).wantsIdFrames());
        assertFalse(CaptureOptions.fromProtocol(false, 4, 2.0, 3_200_000L).wantsIdFrames());
        assertEquals(CaptureProtocol.ID_BURST_FRAMES, CapturePlan.plan(Devices.load(Devices.LOGICAL), o).idFramesPerBurst);
    }

    @Test
    void aCameraWithoutManualSensorIsRefused() {
        CameraFacts auto = Devices.load(Devices.LOGICAL).toBuilder().capabilities(Arrays.asList("backward_compatible"))
                .build();
        assertTrue(assertThrows(UnsupportedCameraException.class, () -> CapturePlan.plan(auto, options(1)))
                .getMessage().contains("MANUAL_SENSOR"));
        CameraFacts noOutputs = Devices.load(Devices.LOGICAL).toBuilder().clearYuvOutputs().build();
        assertThrows(UnsupportedCameraException.class, () -> CapturePlan.plan(noOutputs, options(1)));
    }

    private static double fraction(long ns) {
        double messages = ns / PERIOD_NS;
        return messages - Math.floor(messages);
    }
}
