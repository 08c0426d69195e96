package io.lumipose.client.capture;

import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertNull;
import static org.junit.jupiter.api.Assertions.assertThrows;
import static org.junit.jupiter.api.Assertions.assertTrue;

import org.junit.jupiter.api.Test;

class CaptureSettingsChooserTest {
    private static CameraRanges typical() {
        // A Mi 8-like sensor: 13 us .. 0.68 s, ISO 100..6400, 30 fps stream.
        return new CameraRanges(true, 13_000L, 683_709_000L, 100, 6400, 2_000_000_000L, 33_333_333L);
    }

    @Test
    void positionFrameUsesTenMillisecondsAndMinimumIso() throws Exception {
        CaptureSettings s = CaptureSettingsChooser.choose(typical(), CaptureSettingsChooser.POSITION_EXPOSURE_NS);
        assertEquals(10_000_000L, s.exposureNs);
        assertEquals(0.01, s.exposureS(), 1e-15);
        assertEquals(100, s.sensitivityIso);
        assertEquals(33_333_333L, s.frameDurationNs, "frame duration is at least the stream's minimum");
        assertTrue(s.notes.isEmpty(), s.notes.toString());
    }

    @Test
    void idFrameUsesTheShortExposureParameter() throws Exception {
        CaptureSettings s = CaptureSettingsChooser.choose(typical(), CaptureSettingsChooser.DEFAULT_ID_EXPOSURE_NS);
        assertEquals(125_000L, s.exposureNs);
        CaptureSettings other = CaptureSettingsChooser.choose(typical(), 50_000L);
        assertEquals(50_000L, other.exposureNs);
    }

    @Test
    void exposureIsClampedToTheAdvertisedRange() throws Exception {
        CameraRanges slowOnly = new CameraRanges(true, 20_000_000L, 100_000_000L, 50, 800, null, 0);
        CaptureSettings up = CaptureSettingsChooser.choose(slowOnly, 10_000_000L);
        assertEquals(20_000_000L, up.exposureNs);
        assertEquals(20_000_000L, up.frameDurationNs, "frame is never shorter than its exposure");
        assertEquals(1, up.notes.size());
        assertTrue(up.notes.get(0).contains("clamped"));

        CameraRanges fastOnly = new CameraRanges(true, 1_000L, 5_000_000L, 50, 800, null, 0);
        assertEquals(5_000_000L, CaptureSettingsChooser.choose(fastOnly, 10_000_000L).exposureNs);
        CameraRanges noShort = new CameraRanges(true, 200_000L, 5_000_000L, 50, 800, null, 0);
        assertEquals(200_000L, CaptureSettingsChooser.choose(noShort, 125_000L).exposureNs);
    }

    @Test
    void frameDurationIsClampedToTheMaximum() throws Exception {
        CameraRanges r = new CameraRanges(true, 1_000L, 100_000_000L, 100, 800, 50_000_000L, 66_666_666L);
        CaptureSettings s = CaptureSettingsChooser.choose(r, 10_000_000L);
        assertEquals(50_000_000L, s.frameDurationNs);
        assertTrue(s.notes.get(0).contains("MAX_FRAME_DURATION"));
    }

    @Test
    void missingSensitivityRangeLeavesIsoToTheDeviceAndSaysSo() throws Exception {
        CameraRanges r = new CameraRanges(true, 1_000L, 100_000_000L, null, null, null, 0);
        CaptureSettings s = CaptureSettingsChooser.choose(r, 10_000_000L);
        assertNull(s.sensitivityIso);
        assertTrue(s.notes.get(0).contains("SENSITIVITY_RANGE"));
    }

    @Test
    void refusesWithoutManualSensor() {
        CameraRanges r = new CameraRanges(false, 1_000L, 100_000_000L, 100, 800, null, 0);
        UnsupportedCameraException e = assertThrows(UnsupportedCameraException.class,
                () -> CaptureSettingsChooser.choose(r, 10_000_000L));
        assertTrue(e.getMessage().contains("MANUAL_SENSOR"));
        CameraRanges noRange = new CameraRanges(true, null, null, 100, 800, null, 0);
        assertThrows(UnsupportedCameraException.class, () -> CaptureSettingsChooser.choose(noRange, 10_000_000L));
    }

    @Test
    void focusIsInDioptersAndNoNearerThanTheLensCan() {
        assertEquals(1.0f, CaptureSettingsChooser.focusDiopters(1.0, 10f), 1e-6f);
        assertEquals(0.5f, CaptureSettingsChooser.focusDiopters(2.0, 10f), 1e-6f);
        assertEquals(4.0f, CaptureSettingsChooser.focusDiopters(0.1, 4f), 1e-6f);
        assertNull(CaptureSettingsChooser.focusDiopters(1.0, 0f), "fixed-focus lens");
        assertNull(CaptureSettingsChooser.focusDiopters(1.0, null));
        assertThrows(IllegalArgumentException.class, () -> CaptureSettingsChooser.focusDiopters(0, 10f));
    }

    @Test
    void badRangesAndTargetsAreRejected() {
        assertThrows(IllegalArgumentException.class, () -> new CameraRanges(true, 10L, 5L, 100, 800, null, 0));
        assertThrows(IllegalArgumentException.class, () -> new CameraRanges(true, 1L, 5L, 800, 100, null, 0));
        assertThrows(IllegalArgumentException.class, () -> new CameraRanges(true, 1L, null, 100, 800, null, 0));
        assertThrows(IllegalArgumentException.class, () -> CaptureSettingsChooser.choose(typical(), 0));
    }
}
