package io.lumipose.client.camera;

import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertFalse;
import static org.junit.jupiter.api.Assertions.assertNull;
import static org.junit.jupiter.api.Assertions.assertThrows;
import static org.junit.jupiter.api.Assertions.assertTrue;

import java.util.Arrays;

import org.json.JSONArray;
import org.json.JSONObject;
import org.junit.jupiter.api.Test;

import io.lumipose.client.json.ContractException;
import io.lumipose.client.sensor.LensFacing;

class CameraFactsTest {
    @Test
    void everyFixtureSurvivesARoundTrip() {
        for (String name : Arrays.asList(Devices.LOGICAL, Devices.PRE_CORRECTION, Devices.FRONT_270,
                Devices.PRESET_CURVE_ONLY)) {
            CameraFacts facts = Devices.load(name);
            JSONObject once = facts.toJson();
            assertEquals(once.toString(), CameraFacts.fromJson(once).toJson().toString(), name);
            assertEquals(once.toString(), facts.toBuilder().build().toJson().toString(), name);
        }
    }

    @Test
    void readsTheDocumentedKeys() {
        CameraFacts logical = Devices.load(Devices.LOGICAL);
        assertTrue(logical.isLogicalMultiCamera());
        assertTrue(logical.hasPerFrameControl());
        assertTrue(logical.timestampsAreRealtime());
        assertEquals(LensFacing.BACK, logical.facing());
        assertEquals(3, logical.availableFocalLengthsMm().length);
        assertNull(logical.lensIntrinsicCalibration());
        assertEquals(0.0016, logical.pixelPitchXMm(), 1e-12);
        assertEquals(16_666_666L, logical.minFrameDurationNs(new PixelSize(2000, 1500)));
        assertEquals(Arrays.asList("none", "auto"), logical.rotateAndCropModes);

        CameraFacts pre = Devices.load(Devices.PRE_CORRECTION);
        assertEquals(40, pre.activeArray.left);
        assertEquals(4080, pre.preCorrectionOrActive().width);
        assertNull(pre.rotateAndCropModes, "an API 29 camera has no rotate-and-crop key");

        CameraFacts front = Devices.load(Devices.FRONT_270);
        assertEquals(270, front.sensorOrientationDeg);
        assertEquals(LensFacing.FRONT, front.facing());
        assertEquals(CameraFacts.SYNC_UNKNOWN, front.syncMaxLatency);
        assertFalse(front.timestampsAreRealtime());
        assertTrue(front.distortionCorrectionModes.isEmpty());
        assertEquals(front.activeArray, front.preCorrectionOrActive());
    }

    @Test
    void aFrameCountLatencyIsKept() {
        JSONObject o = Devices.json(Devices.FRONT_270).put("sync_max_latency", 2);
        CameraFacts facts = CameraFacts.fromJson(o);
        assertEquals(2, facts.syncMaxLatency);
        assertFalse(facts.hasPerFrameControl());
        assertEquals(2, facts.toJson().getInt("sync_max_latency"));
    }

    @Test
    void malformedInputNamesTheKey() {
        assertEquals("active_array", field(Devices.json(Devices.LOGICAL).put("active_array", JSONObject.NULL)));
        assertEquals("active_array", field(Devices.json(Devices.LOGICAL).put("active_array", new JSONArray("[0, 0, 4000]"))));
        assertEquals("lens_facing", field(Devices.json(Devices.LOGICAL).put("lens_facing", "sideways")));
        assertEquals("sensor_orientation", field(Devices.json(Devices.LOGICAL).put("sensor_orientation", 45)));
        assertEquals("sync_max_latency", field(Devices.json(Devices.LOGICAL).put("sync_max_latency", "soon")));
        assertEquals("timestamp_source", field(Devices.json(Devices.LOGICAL).put("timestamp_source", "gps")));
        assertEquals("physical_size_mm", field(Devices.json(Devices.LOGICAL).put("physical_size_mm", JSONObject.NULL)));
        assertEquals("available_focal_lengths_mm",
                field(Devices.json(Devices.LOGICAL).put("available_focal_lengths_mm", new JSONArray("[]"))));
        assertEquals("yuv_outputs[0]", field(Devices.json(Devices.LOGICAL).put("yuv_outputs",
                new JSONArray("[[640, 480]]"))));
        assertEquals("exposure_time_range_ns", field(Devices.json(Devices.LOGICAL).put("exposure_time_range_ns",
                new JSONArray("[100, 10]"))));
        assertEquals("capabilities[0]", field(Devices.json(Devices.LOGICAL).put("capabilities", new JSONArray("[1]"))));
        assertEquals("pixel_array[0]", field(Devices.json(Devices.LOGICAL).put("pixel_array", new JSONArray("[4000.5, 3000]"))));
    }

    @Test
    void theBuilderRequiresWhatTheMathsNeeds() {
        ContractException e = assertThrows(ContractException.class, () -> CameraFacts.builder().lensFacing("back")
                .activeArray(ArrayRect.ofSize(4, 3)).pixelArray(new PixelSize(4, 3)).physicalSizeMm(1, 1).build());
        assertEquals("available_focal_lengths_mm", e.field);
    }

    private static String field(JSONObject o) {
        return assertThrows(ContractException.class, () -> CameraFacts.fromJson(o)).field;
    }
}
