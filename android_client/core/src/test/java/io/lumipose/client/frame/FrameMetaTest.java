package io.lumipose.client.frame;

import static org.junit.jupiter.api.Assertions.assertArrayEquals;
import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertFalse;
import static org.junit.jupiter.api.Assertions.assertNull;
import static org.junit.jupiter.api.Assertions.assertThrows;
import static org.junit.jupiter.api.Assertions.assertTrue;

import org.json.JSONObject;
import org.junit.jupiter.api.Test;

import io.lumipose.client.camera.Intrinsics;
import io.lumipose.client.json.ContractException;

class FrameMetaTest {
    private static final Intrinsics K = new Intrinsics(800, 801, 319.5, 239.5,
            new double[] {0.1, -0.2, 0.001, 0.002, 0.03}, 1.4e-6, 4.2e-3, "Pixel 3 back");

    @Test
    void builderWritesTheContractFields() {
        FrameMeta m = FrameMeta.builder(640, 480).camera(K).exposureS(0.01).iso(100.0)
                .rollingShutterSkewS(0.03).timestampNs(123L).gravityCamera(new double[] {0, 0, -1}).build();
        JSONObject o = m.toJson();
        assertEquals("lumipose.frame/1", o.getString("schema"));
        assertEquals("Y8", o.getString("format"));
        assertEquals(640, o.getInt("width"));
        assertEquals(480, o.getInt("height"));
        assertEquals(640, o.getInt("row_stride"));
        assertEquals(800.0, o.getJSONObject("camera").getDouble("fx"));
        assertEquals(0.03, o.getJSONObject("camera").getJSONArray("distortion").getDouble(4));
        assertEquals(0.01, o.getDouble("exposure_s"));
        assertEquals(123L, o.getLong("timestamp_ns"));
        assertEquals(-1.0, o.getJSONArray("gravity_camera").getDouble(2));
        assertFalse(o.has("heading_deg"), "unset optional fields are left out");
        assertEquals(640L * 480, m.frameBytes());
    }

    @Test
    void headerValueIsOneAsciiLine() {
        Intrinsics named = new Intrinsics(800, 800, 319.5, 239.5, null, null, null, "Caméra\nfrontale");
        String h = FrameMeta.builder(640, 480).camera(named).build().toHeaderValue();
        assertFalse(h.contains("\n"));
        for (char c : h.toCharArray()) {
            assertTrue(c >= 0x20 && c < 0x7f, "non-printable or non-ASCII char " + (int) c);
        }
        assertEquals("Caméra\nfrontale", new JSONObject(h).getJSONObject("camera").getString("device"));
    }

    @Test
    void roundTripKeepsEveryFieldAndExtras() {
        FrameMeta m = FrameMeta.builder(640, 480).rowStride(704).camera(K).headingDeg(12.5)
                .extra("note", "bench").build();
        FrameMeta back = FrameMeta.fromJson(m.toJson().toString());
        assertEquals(704, back.rowStride);
        assertEquals(12.5, back.headingDeg);
        assertArrayEquals(K.distortion(), back.camera.distortion(), 0);
        assertEquals("bench", back.toJson().getString("note"));
        assertNull(back.gravityCamera());
    }

    @Test
    void badFieldsAreNamed() {
        assertEquals("row_stride", assertThrows(ContractException.class,
                () -> FrameMeta.builder(640, 480).rowStride(600).camera(K).build()).field);
        assertEquals("width", assertThrows(ContractException.class,
                () -> FrameMeta.builder(0, 480).camera(K).build()).field);
        assertEquals("gravity_camera", assertThrows(ContractException.class,
                () -> FrameMeta.builder(640, 480).camera(K).gravityCamera(new double[] {0, 1}).build()).field);
        assertEquals("camera", assertThrows(ContractException.class,
                () -> FrameMeta.builder(640, 480).build()).field);
        assertEquals("camera.fx", assertThrows(ContractException.class, () -> FrameMeta.fromJson(
                "{\"width\": 4, \"height\": 4, \"camera\": {\"fy\": 1, \"cx\": 1, \"cy\": 1}}")).field);
        assertEquals("width", assertThrows(ContractException.class, () -> FrameMeta.fromJson(
                "{\"width\": \"4\", \"height\": 4, \"camera\": {\"profile\": \"x\"}}")).field);
        assertEquals("schema", assertThrows(ContractException.class, () -> FrameMeta.fromJson(
                "{\"schema\": \"lumipose.frame/2\", \"width\": 4, \"height\": 4, \"camera\": {\"profile\": \"x\"}}"))
                .field);
    }

    /** The gyroscope's rate (docs/contract.md, "Rotation rate") is written, read back and kept by a window. */
    @Test
    void angularVelocityIsWrittenReadAndKeptByAWindow() {
        FrameMeta m = FrameMeta.builder(640, 480).camera(K).timestampNs(7L)
                .angularVelocityCameraDps(new double[] {1.5, -0.25, 30}).build();
        JSONObject o = m.toJson();
        assertEquals(-0.25, o.getJSONArray("angular_velocity_camera_dps").getDouble(1));
        assertEquals(3, o.getJSONArray("angular_velocity_camera_dps").length());
        assertArrayEquals(new double[] {1.5, -0.25, 30},
                FrameMeta.fromJson(o.toString()).angularVelocityCameraDps(), 0);
        assertArrayEquals(new double[] {1.5, -0.25, 30},
                m.window(10, 10, 100, 100, null).angularVelocityCameraDps(), 0);
        assertFalse(FrameMeta.builder(640, 480).camera(K).build().toJson().has("angular_velocity_camera_dps"));
        assertEquals("angular_velocity_camera_dps[2]", assertThrows(ContractException.class, () -> FrameMeta
                .builder(640, 480).camera(K).angularVelocityCameraDps(new double[] {0, 0, 4000.5}).build()).field);
        assertEquals("angular_velocity_camera_dps", assertThrows(ContractException.class, () -> FrameMeta
                .builder(640, 480).camera(K).angularVelocityCameraDps(new double[] {0, 0}).build()).field);
    }

    @Test
    void cropIsAFirstClassFieldAndAWindowKeepsTheFullFramesIntrinsics() {
        FrameMeta whole = FrameMeta.builder(640, 480).camera(K).timestampNs(5L).frameKind("id").toneCurve("linear")
                .build();
        assertNull(whole.crop);
        FrameMeta w = whole.window(100, 50, 200, 120, new double[] {12, 240});
        assertEquals(200, w.width);
        assertEquals(120, w.height);
        assertEquals(200, w.rowStride);
        assertEquals(100, w.crop.x);
        assertEquals(50, w.crop.y);
        assertEquals(640, w.fullWidth());
        assertEquals(480, w.fullHeight());
        assertEquals(319.5, w.camera.cx, "intrinsics describe the full frame");
        assertEquals("id", w.frameKind);
        assertEquals("linear", w.toneCurve);
        JSONObject crop = w.toJson().getJSONObject("crop");
        assertEquals(640, crop.getInt("full_width"));
        FrameMeta back = FrameMeta.fromJson(w.toJson().toString());
        assertEquals(50, back.crop.y);
        assertEquals("linear", back.toJson().getString("tone_curve"));
        FrameMeta inner = w.window(10, 20, 50, 60, new double[] {99, 100});
        assertEquals(110, inner.crop.x, "a window of a window is placed in the full frame");
        assertEquals(70, inner.crop.y);
        assertArrayEquals(new double[] {12, 240}, inner.crop.levelsDn(), 0,
                "a window of a window keeps its frame's levels");
        assertArrayEquals(new double[] {12, 240}, back.crop.levelsDn(), 0);
        assertThrows(ContractException.class, () -> whole.window(0, 0, 10, 10, new double[] {200, 100}));
        assertEquals(200L * 120, w.frameBytes());
    }

    @Test
    void cropMustFitAndToneCurveIsNamed() {
        ContractException e = assertThrows(ContractException.class,
                () -> FrameMeta.builder(400, 300).camera(K).crop(500, 0, 640, 480).build());
        assertTrue(e.getMessage().contains("does not fit"), e.getMessage());
        assertThrows(ContractException.class, () -> FrameMeta.builder(640, 480).camera(K).toneCurve("rec709").build());
        assertEquals("srgb", FrameMeta.builder(640, 480).camera(K).toneCurve("srgb").build().toneCurve);
        FrameMeta built = FrameMeta.builder(400, 300).camera(K).crop(200, 100, 640, 480).build();
        assertEquals(640, built.fullWidth());
    }
}
