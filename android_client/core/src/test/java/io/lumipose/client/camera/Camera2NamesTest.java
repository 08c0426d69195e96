package io.lumipose.client.camera;

import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertNull;

import java.util.Arrays;

import org.junit.jupiter.api.Test;

/** The values are Camera2's public constants (CameraMetadata). */
class Camera2NamesTest {
    @Test
    void camera2ConstantsByName() {
        assertEquals("back", Camera2Names.lensFacing(1)); // LENS_FACING_BACK
        assertEquals("manual_sensor", Camera2Names.capability(1));
        assertEquals("logical_multi_camera", Camera2Names.capability(11));
        assertEquals("realtime", Camera2Names.timestampSource(1));
        assertEquals("uncalibrated", Camera2Names.focusDistanceCalibration(0));
        assertEquals("contrast_curve", Camera2Names.tonemapMode(0));
        assertEquals("preset_curve", Camera2Names.tonemapMode(4));
        assertEquals("srgb", Camera2Names.tonemapPresetCurve(0)); // TONEMAP_PRESET_CURVE_SRGB
        assertEquals("rec709", Camera2Names.tonemapPresetCurve(1));
        assertEquals("minimal", Camera2Names.noiseReductionMode(3));
        assertEquals("none", Camera2Names.rotateAndCrop(0));
        assertEquals(CameraFacts.SYNC_UNKNOWN, Camera2Names.syncMaxLatency(-1));
        assertEquals(CameraFacts.SYNC_PER_FRAME_CONTROL, Camera2Names.syncMaxLatency(0));
        assertEquals(3, Camera2Names.syncMaxLatency(3));
    }

    @Test
    void unknownValuesKeepTheirNumber() {
        assertEquals("42", Camera2Names.capability(42));
        assertEquals(Arrays.asList("off", "17"), Camera2Names.names(new int[] {0, 17}, Camera2Names.EDGE_MODE));
        assertNull(Camera2Names.names(null, Camera2Names.EDGE_MODE));
    }

    /** The Namer constants the app passes (no method references on Android) name as the methods do. */
    @Test
    void namersMatchTheirMethods() {
        for (int v = -1; v < 20; v++) {
            assertEquals(Camera2Names.capability(v), Camera2Names.CAPABILITY.name(v));
            assertEquals(Camera2Names.oisMode(v), Camera2Names.OIS_MODE.name(v));
            assertEquals(Camera2Names.tonemapMode(v), Camera2Names.TONEMAP_MODE.name(v));
            assertEquals(Camera2Names.edgeMode(v), Camera2Names.EDGE_MODE.name(v));
            assertEquals(Camera2Names.noiseReductionMode(v), Camera2Names.NOISE_REDUCTION_MODE.name(v));
            assertEquals(Camera2Names.distortionCorrectionMode(v), Camera2Names.DISTORTION_CORRECTION_MODE.name(v));
            assertEquals(Camera2Names.rotateAndCrop(v), Camera2Names.ROTATE_AND_CROP_MODE.name(v));
        }
    }
}
