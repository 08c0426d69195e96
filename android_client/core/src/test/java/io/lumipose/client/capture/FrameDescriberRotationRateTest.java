package io.lumipose.client.capture;

import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertFalse;
import static org.junit.jupiter.api.Assertions.assertNull;
import static org.junit.jupiter.api.Assertions.assertTrue;

import org.json.JSONArray;
import org.json.JSONObject;
import org.junit.jupiter.api.Test;

import io.lumipose.client.camera.CameraFacts;
import io.lumipose.client.camera.Devices;
import io.lumipose.client.camera.FrameResult;

/** The frame JSON's {@code angular_velocity_camera_dps}, from the gyroscope's device-frame reading. */
class FrameDescriberRotationRateTest {
    /** 0.5 rad/s about the device's y axis (the phone's long side), 0.1 about its z axis. */
    private static final float[] RATE = {0, 0.5f, 0.1f};

    private static FrameDescriber.Described describePose(String device, float[] rateDevice) throws Exception {
        CameraFacts facts = Devices.load(device);
        CapturePlan plan = CapturePlan.plan(facts, new CaptureOptions(8_400_000L, 125_000L, 1, 2.0, 3_200_000L));
        // A logical camera's result names the lens that took the frame.
        double focalLengthMm = Devices.LOGICAL.equals(device) ? 4.8 : 3.52;
        FrameResult result = FrameResult.builder(55L).request("pose").exposureNs(plan.pose.exposureNs)
                .sensitivityIso(plan.pose.sensitivityIso).rollingShutterSkewNs(20_000_000L)
                .focalLengthMm(focalLengthMm).build();
        FrameDescriber.Described d = new FrameDescriber(facts, plan, null).describe(result, null, null, rateDevice);
        assertNull(d.dropReason);
        return d;
    }

    private static JSONObject describedPose(String device, float[] rateDevice) throws Exception {
        return describePose(device, rateDevice).meta.toJson();
    }

    @Test
    void theBackCameraAt90TurnsTheRateAsItTurnsGravity() throws Exception {
        JSONArray w = describedPose(Devices.LOGICAL, RATE).getJSONArray("angular_velocity_camera_dps");
        // Back at 90: camera x = device -y, y = device -x, z = device -z.
        assertEquals(-Math.toDegrees(0.5), w.getDouble(0), 1e-4);
        assertEquals(0, w.getDouble(1), 1e-9);
        assertEquals(-Math.toDegrees(0.1), w.getDouble(2), 1e-4);
    }

    @Test
    void theFrontCameraAt270TurnsTheRateAsItTurnsGravity() throws Exception {
        JSONArray w = describedPose(Devices.FRONT_270, RATE).getJSONArray("angular_velocity_camera_dps");
        // Front at 270: camera x = device +y, y = device -x, z = device +z.
        assertEquals(Math.toDegrees(0.5), w.getDouble(0), 1e-4);
        assertEquals(0, w.getDouble(1), 1e-9);
        assertEquals(Math.toDegrees(0.1), w.getDouble(2), 1e-4);
    }

    @Test
    void noReadingNoField() throws Exception {
        assertFalse(describedPose(Devices.LOGICAL, null).has("angular_velocity_camera_dps"));
    }

    /** A reading beyond the contract's range costs the frame its rate, not the frame. */
    @Test
    void aWildReadingIsLeftOutWithAWarning() throws Exception {
        FrameDescriber.Described d = describePose(Devices.LOGICAL, new float[] {0, 0, 80}); // 4584 deg/s
        assertNull(d.meta.angularVelocityCameraDps());
        assertTrue(d.warnings.stream().anyMatch(w -> w.contains("4000 deg/s")), d.warnings.toString());
    }
}
