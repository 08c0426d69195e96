package io.lumipose.client.camera;

import static org.junit.jupiter.api.Assertions.assertArrayEquals;
import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertNull;
import static org.junit.jupiter.api.Assertions.assertThrows;

import org.json.JSONObject;
import org.junit.jupiter.api.Test;

import io.lumipose.client.json.ContractException;

class FrameResultTest {
    @Test
    void roundTripsEveryKey() {
        FrameResult r = FrameResult.builder(123_456_789_012L).request("id").exposureNs(125_000L).sensitivityIso(800)
                .frameDurationNs(18_900_000L).rollingShutterSkewNs(30_000_000L).focalLengthMm(4.8)
                .lensIntrinsicCalibration(new double[] {3000, 3000, 2000, 1500, 0})
                .lensDistortion(new double[] {0.1, 0, 0, 0, 0}).lensRadialDistortion(new double[] {1, 0, 0, 0, 0, 0})
                .cropRegion(new ArrayRect(0, 0, 4000, 3000)).zoomRatio(1.0).oisMode("off").tonemapMode("preset_curve")
                .tonemapPresetCurve("srgb").focusDistanceDiopters(0.5).rotateAndCrop("none")
                .distortionCorrectionMode("off").build();
        JSONObject o = r.toJson();
        assertEquals(123_456_789_012L, o.getLong("sensor_timestamp_ns"));
        assertEquals(800, o.getInt("sensor_sensitivity"));
        assertEquals("[0,0,4000,3000]", o.getJSONArray("scaler_crop_region").toString());
        assertEquals("srgb", o.getString("tonemap_preset_curve"));
        FrameResult back = FrameResult.fromJson(o);
        assertEquals(o.toString(), back.toJson().toString());
        assertArrayEquals(new double[] {3000, 3000, 2000, 1500, 0}, back.lensIntrinsicCalibration(), 0);
        assertEquals(o.toString(), r.toBuilder().build().toJson().toString());
    }

    @Test
    void onlyTheTimestampIsRequired() {
        FrameResult r = FrameResult.fromJson(new JSONObject("{\"sensor_timestamp_ns\": 5, \"request\": null}"));
        assertEquals(5L, r.timestampNs);
        assertNull(r.request);
        assertNull(r.exposureNs);
        assertNull(r.cropRegion);
        assertEquals("sensor_timestamp_ns", assertThrows(ContractException.class,
                () -> FrameResult.fromJson(new JSONObject("{\"request\": \"pose\"}"))).field);
        assertEquals("request", assertThrows(ContractException.class,
                () -> FrameResult.fromJson(new JSONObject("{\"sensor_timestamp_ns\": 5, \"request\": \"video\"}"))).field);
        assertEquals("sensor_exposure_time_ns", assertThrows(ContractException.class, () -> FrameResult.fromJson(
                new JSONObject("{\"sensor_timestamp_ns\": 5, \"sensor_exposure_time_ns\": \"1\"}"))).field);
        assertEquals("scaler_crop_region", assertThrows(ContractException.class, () -> FrameResult.fromJson(
                new JSONObject("{\"sensor_timestamp_ns\": 5, \"scaler_crop_region\": [0, 0, 0, 10]}"))).field);
    }
}
