package io.lumipose.client.capture;

import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertThrows;
import static org.junit.jupiter.api.Assertions.assertTrue;

import org.junit.jupiter.api.Test;

import io.lumipose.client.protocol.CaptureProtocol;

class IdCapturePlanTest {
    private static final CameraRanges MI8 = new CameraRanges(true, 13_000L, 683_709_000L, 100, 6400,
            2_000_000_000L, 33_333_333L);

    @Test
    void messagePeriodIs21ChipsAt2500Hz() {
        assertEquals(8_400_000L, IdCapturePlan.messagePeriodNs());
    }

    @Test
    void intervalAdvancesThePhaseByTheGoldenStep() {
        // 33.3 ms / 8.4 ms - 0.382 = 3.59 -> 4 whole periods + 0.382.
        long ns = IdCapturePlan.steppedIntervalNs(33_333_333L, 33_333_333L, CaptureProtocol.GOLDEN_STEP);
        assertEquals(Math.round((4 + (3 - Math.sqrt(5)) / 2) * 8_400_000L), ns);
        double phase = (ns / 8_400_000.0) % 1.0;
        assertEquals(0.381966, phase, 1e-6);
        assertTrue(ns >= 33_333_333L);
    }

    @Test
    void intervalNeverUndercutsTheStreamMinimum() {
        // Nominal 30 ms rounds down to 3.382 periods = 28.4 ms, below a 30 ms minimum: one more period.
        long ns = IdCapturePlan.steppedIntervalNs(30_000_000L, 30_000_000L, CaptureProtocol.GOLDEN_STEP);
        assertEquals(Math.round(4.381966011250105 * 8_400_000L), ns);
        assertThrows(IllegalArgumentException.class, () -> IdCapturePlan.steppedIntervalNs(0, 0, 0.25));
        assertThrows(IllegalArgumentException.class, () -> IdCapturePlan.steppedIntervalNs(30_000_000L, 0, 1.0));
    }

    @Test
    void idFramesUseTheShortExposureAndRaiseIso() throws Exception {
        CaptureSettings pose = CaptureSettingsChooser.choose(MI8, CaptureSettingsChooser.POSITION_EXPOSURE_NS);
        CaptureSettings id = IdCapturePlan.choose(MI8, CaptureSettingsChooser.DEFAULT_ID_EXPOSURE_NS, pose,
                IdCapturePlan.DEFAULT_BRIGHTNESS_FRACTION);
        assertEquals(125_000L, id.exposureNs);
        // 100 ISO x (10 ms / 0.125 ms) x 0.2 = 1600.
        assertEquals(1600, id.sensitivityIso);
        // A burst of 4 frames a quarter message apart: 4.25 periods = 35.70 ms at 30 fps (docs/vlc.md).
        assertEquals(35_700_000L, id.frameDurationNs);
        assertEquals(4, IdCapturePlan.BURST_FRAMES);
        assertTrue(id.notes.isEmpty(), id.notes.toString());
    }

    @Test
    void isoIsClamped() throws Exception {
        CameraRanges lowIso = new CameraRanges(true, 13_000L, 683_709_000L, 100, 800, null, 33_333_333L);
        CaptureSettings pose = CaptureSettingsChooser.choose(lowIso, CaptureSettingsChooser.POSITION_EXPOSURE_NS);
        CaptureSettings id = IdCapturePlan.choose(lowIso, 125_000L, pose, 0.2);
        assertEquals(800, id.sensitivityIso);
        assertTrue(id.notes.get(0).contains("clamped"), id.notes.toString());
        assertThrows(IllegalArgumentException.class, () -> IdCapturePlan.choose(lowIso, 125_000L, pose, 0));
    }

    @Test
    void idExposuresUpToTheServersLimitAreTakenLongerOnesRefused() throws Exception {
        // the server reads ID frames up to one chip (1/2500 s) and refuses longer ones
        assertEquals(400_000L, CaptureProtocol.ID_MAX_EXPOSURE_NS);
        CaptureSettings pose = CaptureSettingsChooser.choose(MI8, CaptureSettingsChooser.POSITION_EXPOSURE_NS);
        CaptureSettings atLimit = IdCapturePlan.choose(MI8, CaptureProtocol.ID_MAX_EXPOSURE_NS, pose, 0.2);
        assertEquals(CaptureProtocol.ID_MAX_EXPOSURE_NS, atLimit.exposureNs);
        UnsupportedCameraException refused = assertThrows(UnsupportedCameraException.class,
                () -> IdCapturePlan.choose(MI8, CaptureProtocol.ID_MAX_EXPOSURE_NS + 1, pose, 0.2));
        assertTrue(refused.getMessage().contains("averaged away"), refused.getMessage());
        // nor when the camera cannot expose that short
        CameraRanges slowSensor = new CameraRanges(true, 500_000L, 683_709_000L, 100, 6400, null, 33_333_333L);
        assertThrows(UnsupportedCameraException.class, () -> IdCapturePlan.choose(slowSensor,
                CaptureProtocol.ID_EXPOSURE_NS, CaptureSettingsChooser.choose(slowSensor, 10_000_000L), 0.2));
    }
}
