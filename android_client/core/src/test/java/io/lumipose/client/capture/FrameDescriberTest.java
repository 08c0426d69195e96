package io.lumipose.client.capture;

import static org.junit.jupiter.api.Assertions.assertArrayEquals;
import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertNull;
import static org.junit.jupiter.api.Assertions.assertTrue;

import org.junit.jupiter.api.Test;

import io.lumipose.client.camera.ArrayRect;
import io.lumipose.client.camera.CameraFacts;
import io.lumipose.client.camera.DeviceProfile;
import io.lumipose.client.camera.Devices;
import io.lumipose.client.camera.FrameResult;
import io.lumipose.client.frame.FrameMeta;

class FrameDescriberTest {
    private static final float[] SCREEN_UP = {0, 0, 9.81f};
    private static final float[] IDENTITY = {1, 0, 0, 0, 1, 0, 0, 0, 1};

    private final CameraFacts facts = Devices.load(Devices.LOGICAL);
    private final CapturePlan plan = plan(facts, 4);
    private final FrameDescriber describer = new FrameDescriber(facts, plan, null);

    private static CapturePlan plan(CameraFacts facts, int beacons) {
        try {
            return CapturePlan.plan(facts, new CaptureOptions(8_400_000L, 125_000L, beacons, 2.0, 3_200_000L));
        } catch (UnsupportedCameraException e) {
            throw new AssertionError(e);
        }
    }

    /** What the device reports when it did as asked. */
    private static FrameResult.Builder asAsked(RequestSpec spec, long timestampNs) {
        return FrameResult.builder(timestampNs).request(spec.kind).exposureNs(spec.exposureNs)
                .sensitivityIso(spec.sensitivityIso).frameDurationNs(spec.frameDurationNs)
                .rollingShutterSkewNs(20_000_000L).focalLengthMm(4.8).cropRegion(spec.cropRegion)
                .oisMode("off").tonemapMode("contrast_curve").distortionCorrectionMode("off").zoomRatio(1.0)
                .rotateAndCrop("none");
    }

    @Test
    void aPoseFrameInTheContractsUnits() {
        FrameDescriber.Described d = describer.describe(asAsked(plan.pose, 55L).build(), SCREEN_UP, null);
        assertNull(d.dropReason);
        assertEquals("pose", d.kind);
        FrameMeta m = d.meta;
        assertEquals(2000, m.width);
        assertEquals(2000, m.rowStride);
        assertEquals(0.0084, m.exposureS, 1e-15);
        assertEquals(50.0, m.iso);
        assertEquals(0.02, m.rollingShutterSkewS, 1e-15);
        assertEquals(55L, m.timestampNs);
        assertEquals("pose", m.frameKind);
        assertEquals(1500, m.camera.fx, 1e-9); // from the result's 4.8 mm (DeviceIntrinsicsTest)
        assertEquals("linear", m.toJson().getString("tone_curve"));
        // Screen up, the back camera looks at the floor: gravity points along its optical axis.
        assertArrayEquals(new double[] {0, 0, 1}, m.gravityCamera(), 1e-12);
        assertNull(m.headingDeg, "no map bearing, no heading");
    }

    @Test
    void anIdFrameIsKnownByItsExposure() {
        FrameDescriber.Described d = describer.describe(asAsked(plan.id, 56L).build(), null, null);
        assertEquals("id", d.kind);
        assertEquals("id", d.meta.frameKind);
        assertEquals(0.000125, d.meta.exposureS, 1e-15);
        // Untagged results are classified the same way.
        assertEquals("id", describer.describe(asAsked(plan.id, 57L).request(null).build(), null, null).meta.frameKind);
    }

    /**
     * Issue 12 item 3: without per-frame control the settings reach the sensor frames after their
     * request, so the tags run ahead of the exposures (a repeating pose + 4 ID burst with a lag of
     * L frames never lines up). The result, not the tag, says what the frame is.
     */
    @Test
    void aFrameIsWhatItsResultShowsWhateverItsTag() {
        CameraFacts lagging = facts.toBuilder().syncMaxLatency(CameraFacts.SYNC_UNKNOWN).build();
        FrameDescriber late = new FrameDescriber(lagging, plan, null);
        FrameDescriber.Described id = late.describe(asAsked(plan.id, 58L).request("pose").build(), SCREEN_UP, null);
        assertEquals("id", id.meta.frameKind, "tagged pose, taken with the ID exposure");
        FrameDescriber.Described pose = late.describe(asAsked(plan.pose, 59L).request("id").build(), SCREEN_UP, null);
        assertEquals("pose", pose.meta.frameKind, "tagged id, taken with the pose exposure");
        assertEquals(0.0084, pose.meta.exposureS, 1e-15);
        assertEquals(1, id.warnings.size());
        assertEquals(id.warnings, pose.warnings, "one text, so the screen says it once");
        assertTrue(id.warnings.get(0).contains("SYNC_MAX_LATENCY unknown"), id.warnings.get(0));
        assertTrue(late.describe(asAsked(plan.pose, 60L).build(), null, null).warnings.isEmpty(), "tag and result agree");

        // A device that claims per-frame control and still lags: the result is the truth, with a warning.
        FrameDescriber.Described claimed = describer.describe(asAsked(plan.id, 61L).request("pose").build(), null, null);
        assertEquals("id", claimed.meta.frameKind);
        assertTrue(claimed.warnings.get(0).contains("although SYNC_MAX_LATENCY is per_frame_control"),
                claimed.warnings.toString());
    }

    /** A frame whose result matches neither request (settings in transition) is dropped, and says so. */
    @Test
    void aFrameMatchingNeitherRequestIsDropped() {
        FrameResult neither = asAsked(plan.pose, 62L).exposureNs(4_000_000L).build();
        FrameDescriber.Described d = describer.describe(neither, SCREEN_UP, null);
        assertNull(d.meta);
        assertNull(d.kind);
        assertTrue(d.dropReason.contains("match neither"), d.dropReason);
        assertTrue(d.dropReason.contains("settings in transition"), d.dropReason);

        FrameResult otherIso = asAsked(plan.pose, 63L).sensitivityIso(400).build();
        assertNull(describer.describe(otherIso, SCREEN_UP, null).meta);
        // 2 % off is within tolerance: sensors round exposure to whole rows.
        assertEquals("pose", describer.describe(asAsked(plan.pose, 64L).exposureNs(8_568_000L).build(), null, null)
                .meta.frameKind);
    }

    @Test
    void aFrameWithAnotherCropOrNoSkewIsDropped() {
        FrameResult cropped = asAsked(plan.pose, 62L).cropRegion(new ArrayRect(500, 375, 3000, 2250)).build();
        assertTrue(describer.describe(cropped, null, null).dropReason.contains("SCALER_CROP_REGION"));
        FrameResult noSkew = asAsked(plan.id, 63L).rollingShutterSkewNs(null).build();
        assertEquals("no rolling-shutter skew: beacon IDs off", describer.describe(noSkew, null, null).dropReason);
        FrameResult zoomed = asAsked(plan.pose, 64L).zoomRatio(2.0).build();
        assertTrue(describer.describe(zoomed, null, null).dropReason.contains("CONTROL_ZOOM_RATIO"));
    }

    @Test
    void theToneCurveIsWhatTheResultSays() {
        FrameResult deviceCurve = asAsked(plan.pose, 65L).tonemapMode("fast").build();
        assertEquals("device", describer.describe(deviceCurve, null, null).meta.toJson().getString("tone_curve"));
        FrameResult unreported = asAsked(plan.pose, 66L).tonemapMode(null).build();
        assertEquals("device", describer.describe(unreported, null, null).meta.toJson().getString("tone_curve"));
        // the preset's curve is known whoever asked for it; another preset is the device's to the server
        FrameResult srgb = asAsked(plan.pose, 69L).tonemapMode("preset_curve").tonemapPresetCurve("srgb").build();
        assertEquals("srgb", describer.describe(srgb, null, null).meta.toJson().getString("tone_curve"));
        FrameResult rec709 = asAsked(plan.pose, 70L).tonemapMode("preset_curve").tonemapPresetCurve("rec709").build();
        assertEquals("device", describer.describe(rec709, null, null).meta.toJson().getString("tone_curve"));
    }

    /** A device with the preset curve only: the plan asks for sRGB and the frames that got it say "srgb". */
    @Test
    void aPresetCurveDeviceSaysSrgbWhenTheResultShowsIt() {
        CameraFacts presetOnly = Devices.load(Devices.PRESET_CURVE_ONLY);
        CapturePlan presetPlan = plan(presetOnly, 4);
        FrameDescriber d = new FrameDescriber(presetOnly, presetPlan, null);
        for (RequestSpec spec : presetPlan.burst()) {
            FrameResult applied = asAsked(spec, 71L).tonemapMode("preset_curve").tonemapPresetCurve("srgb").build();
            FrameDescriber.Described described = d.describe(applied, null, null);
            assertEquals(spec.kind, described.kind);
            assertEquals("srgb", described.meta.toJson().getString("tone_curve"), spec.kind);
            FrameResult ignored = asAsked(spec, 72L).tonemapMode("fast").build(); // the request not honoured
            assertEquals("device", d.describe(ignored, null, null).meta.toJson().getString("tone_curve"), spec.kind);
        }
    }

    @Test
    void warningsReachTheCaller() {
        FrameResult ois = asAsked(plan.pose, 67L).oisMode("on").lensDistortion(new double[] {1, 2}).build();
        FrameDescriber.Described d = describer.describe(ois, null, null);
        assertEquals("pose", d.meta.frameKind);
        assertEquals(2, d.warnings.size(), d.warnings.toString());
    }

    /** Front camera at 270: gravity and heading go through the camera mount; one kind of frame without ID frames. */
    @Test
    void frontCameraGravityAndHeading() {
        CameraFacts front = Devices.load(Devices.FRONT_270);
        CapturePlan poseOnly = plan(front, 1);
        FrameDescriber d = new FrameDescriber(front, poseOnly, 90.0);
        FrameMeta m = d.describe(FrameResult.builder(1L).exposureNs(8_400_000L).sensitivityIso(100).build(),
                SCREEN_UP, IDENTITY).meta;
        // Screen up, the front camera looks at the ceiling: gravity points back along its optical axis.
        assertArrayEquals(new double[] {0, 0, -1}, m.gravityCamera(), 1e-12);
        assertEquals(90.0, m.headingDeg, 1e-9);
        assertEquals("device", m.toJson().getString("tone_curve"), "no contrast curve on this camera");
        // Without an exposure in the result a pose-only plan still knows the kind; with ID frames it cannot.
        assertEquals("pose", d.describe(FrameResult.builder(2L).build(), null, null).kind);
        assertNull(new FrameDescriber(facts, plan, null).describe(FrameResult.builder(3L).build(), null, null).meta);
    }

    @Test
    void anExternalCameraSendsNoGravity() {
        CameraFacts external = facts.toBuilder().lensFacing("external").build();
        FrameMeta m = new FrameDescriber(external, plan, 90.0).describe(asAsked(plan.pose, 68L).build(), SCREEN_UP,
                IDENTITY).meta;
        assertNull(m.gravityCamera(), "an external camera's attitude is unknown");
        assertNull(m.headingDeg);
    }

    /** Every frame says where its image's +x points on the compass; the heading needs the map's bearing too. */
    @Test
    void compassBearingGoesWithOrWithoutAMapBearing() {
        CameraFacts front = Devices.load(Devices.FRONT_270);
        CapturePlan poseOnly = plan(front, 1);
        FrameResult r = FrameResult.builder(1L).exposureNs(8_400_000L).sensitivityIso(100).build();
        // Screen up, top north: the front sensor's image x is the device's +y, north: bearing 0.
        FrameMeta alone = new FrameDescriber(front, poseOnly, null).describe(r, SCREEN_UP, IDENTITY).meta;
        assertEquals(0.0, alone.compassBearingDeg, 1e-9);
        assertNull(alone.headingDeg, "no map bearing, no heading");
        float[] east = {0, 1, 0, -1, 0, 0, 0, 0, 1}; // top (device y) east, device x south
        FrameMeta turned = new FrameDescriber(front, poseOnly, 90.0).describe(r, SCREEN_UP, east).meta;
        assertEquals(90.0, turned.compassBearingDeg, 1e-6);
        assertEquals(0.0, turned.headingDeg, 1e-6, "image x east, map +X east: yaw 0");
        assertNull(new FrameDescriber(front, poseOnly, 90.0).describe(r, SCREEN_UP, null).meta.compassBearingDeg);
    }

    /** A calibrated profile's pinhole replaces Camera2's, scaled to the output; another lens keeps Camera2's. */
    @Test
    void aCalibratedProfileGivesTheFramesItsIntrinsics() {
        int w = plan.output.width;
        int h = plan.output.height;
        DeviceProfile calibrated = new DeviceProfile("phone-calibrated", "phone", "unknown", "rear", 3.2e-6, 4.8e-3,
                2 * w, 2 * h, new double[] {0.1, -0.2, 0, 0, 0.05}, 0.1,
                new DeviceProfile.MeasuredPinhole(3010.0, 3008.0, w - 0.5 + 3, h - 0.5 - 2, 0.21, 25));
        FrameDescriber.Described d = new FrameDescriber(facts, plan, null, calibrated)
                .describe(asAsked(plan.pose, 70L).build(), SCREEN_UP, null);
        assertEquals(1505.0, d.meta.camera.fx, 1e-9, "half the profile's size: half its focal length");
        assertEquals(1504.0, d.meta.camera.fy, 1e-9);
        assertEquals((w - 1) / 2.0 + 1.5, d.meta.camera.cx, 1e-9);
        assertEquals((h - 1) / 2.0 - 1.0, d.meta.camera.cy, 1e-9);
        assertArrayEquals(new double[] {0.1, -0.2, 0, 0, 0.05}, d.meta.camera.distortion(), 0.0);
        FrameDescriber.Described other = new FrameDescriber(facts, plan, null, calibrated)
                .describe(asAsked(plan.pose, 71L).focalLengthMm(2.2).build(), SCREEN_UP, null);
        assertTrue(other.meta.camera.fx < 1000, "the ultra-wide's own intrinsics, not the calibration's");
        assertTrue(other.warnings.toString().contains("calibration 'phone-calibrated' not used"), other.warnings
                .toString());
    }
}
