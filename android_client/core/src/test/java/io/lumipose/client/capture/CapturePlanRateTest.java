package io.lumipose.client.capture;

import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertTrue;

import java.util.List;

import org.junit.jupiter.api.Test;

import io.lumipose.client.camera.CameraFacts;
import io.lumipose.client.camera.Devices;
import io.lumipose.client.protocol.CaptureProtocol;

/**
 * Battery and heat (issue 26): the repeating burst runs at a stated rate, not the sensor's fastest
 * (every frame is read out and processed whether the uploader takes it or not). The burst's last
 * frame carries the blanking; the pose and ID frames keep their exposures and shortest durations,
 * the ID frames back to back a quarter message apart, the period golden-stepped.
 */
class CapturePlanRateTest {
    private static final double PERIOD_NS = IdCapturePlan.messagePeriodNs(); // 8.4 ms
    private static final long MS = 1_000_000L;

    private static CaptureOptions options(int beacons) {
        return new CaptureOptions(8_400_000L, 125_000L, beacons, 2.0, 3_200_000L);
    }

    private static long period(CapturePlan plan) {
        long sum = 0;
        for (RequestSpec spec : plan.burst()) {
            sum += spec.frameDurationNs;
        }
        return sum;
    }

    private static double fraction(long ns) {
        double messages = ns / PERIOD_NS;
        return messages - Math.floor(messages);
    }

    /**
     * The logical camera at 2000x1500 (16.67 ms a frame at the shortest): bursts with ID frames 5
     * a second, the smallest golden-stepped period of at least 200 ms, 24.382 messages = 204.81 ms
     * (it was 95.61 ms, 52 frames a second); the pose frame and the first three ID frames at their
     * own shortest, the last ID frame 131.44 ms.
     */
    @Test
    void aLiveBurstWithIdFramesRepeatsAtMostFiveTimesASecondStillGoldenStepped() throws Exception {
        CapturePlan plan = CapturePlan.plan(Devices.load(Devices.LOGICAL), options(4));
        List<RequestSpec> burst = plan.burst();
        assertEquals(5, burst.size());
        long period = period(plan);
        assertEquals(plan.burstIntervalNs, period);
        assertEquals(24.0 + CaptureProtocol.GOLDEN_STEP, period / PERIOD_NS, 1e-6);
        assertTrue(period >= 200 * MS && period < 200 * MS + PERIOD_NS, "at most 5 a second: " + period);
        assertEquals(CaptureOptions.LIVE_ID_BURSTS_PER_S, plan.burstsPerSecond, 0);
        assertEquals(16_666_666L, burst.get(0).frameDurationNs, "the ID frames follow the pose frame at once");
        for (int i = 1; i < 4; i++) {
            assertEquals(18_900_000L, burst.get(i).frameDurationNs, "ID frames back to back, 2.25 messages");
            assertEquals(0.25, fraction(burst.get(i).frameDurationNs), 1e-6);
        }
        assertEquals(period - 16_666_666L - 3 * 18_900_000L, burst.get(4).frameDurationNs, "the blanking");
        // The exposures are the protocol's, as before.
        assertEquals(8_400_000L, burst.get(0).exposureNs);
        assertEquals(Integer.valueOf(50), burst.get(0).sensitivityIso);
        for (RequestSpec id : burst.subList(1, 5)) {
            assertEquals(RequestSpec.ID, id.kind);
            assertEquals(125_000L, id.exposureNs);
            assertEquals(Integer.valueOf(672), id.sensitivityIso);
            assertEquals(plan.pose.cropRegion, id.cropRegion);
        }
    }

    /** Pose frames only (a one-beacon map, or no rolling-shutter skew): 10 a second, not 60. */
    @Test
    void poseFramesAloneRepeatTenTimesASecond() throws Exception {
        CapturePlan plan = CapturePlan.plan(Devices.load(Devices.LOGICAL), options(1));
        assertEquals(1, plan.burst().size());
        assertEquals(100 * MS, plan.pose.frameDurationNs);
        assertEquals(100 * MS, plan.burstIntervalNs);
        assertEquals(8_400_000L, plan.pose.exposureNs);
        CapturePlan noSkew = CapturePlan.plan(Devices.load(Devices.LOGICAL), options(4))
                .withoutIdFrames("no rolling-shutter skew: beacon IDs off");
        assertEquals(100 * MS, noSkew.pose.frameDurationNs);
        assertEquals(8_400_000L, noSkew.pose.exposureNs);
    }

    /** Still photos (the calibration board) need a preview five times a second, nothing more. */
    @Test
    void stillsRepeatFiveTimesASecond() throws Exception {
        CameraFacts facts = Devices.load(Devices.LOGICAL);
        CapturePlan stills = CapturePlan.plan(facts, options(4)).forStills(facts, 20 * MS, 800);
        assertEquals(1, stills.burst().size());
        assertEquals(200 * MS, stills.pose.frameDurationNs);
        assertEquals(200 * MS, stills.burstIntervalNs);
        assertEquals(20 * MS, stills.pose.exposureNs);
        assertEquals(Integer.valueOf(800), stills.pose.sensitivityIso);
    }

    /**
     * No frame may last longer than SENSOR_INFO_MAX_FRAME_DURATION: at 50 ms pose frames go 20 a
     * second, said. At 25 ms the ID burst's last frame cannot take the 131.44 ms of a 204.81 ms
     * period: the longest golden-stepped period within it, 11.382 messages (95.61 ms, the last
     * frame 22.24 ms), said. At 20 ms no golden-stepped period fits (the shortest, 95.61 ms,
     * needs those 22.24 ms): the last frame at the maximum, said.
     */
    @Test
    void aShortMaximumFrameDurationCapsTheBlankingAndSaysSo() throws Exception {
        CameraFacts fifty = Devices.load(Devices.LOGICAL).toBuilder().maxFrameDurationNs(50 * MS).build();
        CapturePlan poseOnly = CapturePlan.plan(fifty, options(1));
        assertEquals(50 * MS, poseOnly.pose.frameDurationNs);
        assertEquals(8_400_000L, poseOnly.pose.exposureNs);
        assertTrue(poseOnly.notes.stream().anyMatch(n -> n.contains("SENSOR_INFO_MAX_FRAME_DURATION")),
                poseOnly.notes.toString());

        CameraFacts quarter = Devices.load(Devices.LOGICAL).toBuilder().maxFrameDurationNs(25 * MS).build();
        CapturePlan bursts = CapturePlan.plan(quarter, options(4));
        long period = period(bursts);
        assertEquals(11.0 + CaptureProtocol.GOLDEN_STEP, period / PERIOD_NS, 1e-6);
        List<RequestSpec> burst = bursts.burst();
        assertEquals(16_666_666L, burst.get(0).frameDurationNs);
        assertEquals(18_900_000L, burst.get(3).frameDurationNs);
        assertEquals(period - 16_666_666L - 3 * 18_900_000L, burst.get(4).frameDurationNs);
        assertTrue(burst.get(4).frameDurationNs <= 25 * MS, "within the camera's maximum");
        assertEquals(125_000L, burst.get(4).exposureNs);
        assertTrue(bursts.notes.stream().anyMatch(n -> n.contains("SENSOR_INFO_MAX_FRAME_DURATION")),
                bursts.notes.toString());

        CameraFacts twenty = Devices.load(Devices.LOGICAL).toBuilder().maxFrameDurationNs(20 * MS).build();
        CapturePlan tight = CapturePlan.plan(twenty, options(4));
        List<RequestSpec> t = tight.burst();
        assertEquals(20 * MS, t.get(4).frameDurationNs);
        assertEquals(16_666_666L + 3 * 18_900_000L + 20 * MS, period(tight));
        assertEquals(18_900_000L, t.get(1).frameDurationNs, "the ID frames keep their step");
        assertTrue(tight.notes.stream().anyMatch(n -> n.contains("not golden-stepped")), tight.notes.toString());
        for (RequestSpec spec : t) {
            assertTrue(spec.frameDurationNs <= 20 * MS, spec.kind + " " + spec.frameDurationNs);
        }
    }

    /**
     * The Mi 8-sized front camera at 1296x970 (33.3 ms a frame at the shortest): its shortest
     * burst, 21.382 messages = 179.61 ms, is still 5.6 a second; at 5 a second 24.382 messages =
     * 204.81 ms, the pose frame at 33.33 ms (it took the golden step's slack, 36.81 ms, before).
     * A rate the shortest burst cannot reach leaves it at its shortest.
     */
    @Test
    void theFrontCameraSlowsALittleAndASlowRateIsTheShortestBurst() throws Exception {
        CaptureOptions live = new CaptureOptions(8_400_000L, 125_000L, 4, 2.0, 1_300_000L);
        CapturePlan plan = CapturePlan.plan(Devices.load(Devices.FRONT_270), live);
        assertEquals(24.0 + CaptureProtocol.GOLDEN_STEP, period(plan) / PERIOD_NS, 1e-6);
        assertEquals(33_333_333L, plan.burst().get(0).frameDurationNs);
        assertEquals(35_700_000L, plan.burst().get(1).frameDurationNs);
        CapturePlan fast = CapturePlan.plan(Devices.load(Devices.FRONT_270), live.withBurstsPerSecond(10, 10));
        assertEquals(21.0 + CaptureProtocol.GOLDEN_STEP, period(fast) / PERIOD_NS, 1e-6);
        assertEquals(35_700_000L, fast.burst().get(3).frameDurationNs);
    }
}
