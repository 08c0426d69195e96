package io.lumipose.client.camera;

import java.io.IOException;
import java.io.InputStream;
import java.nio.charset.StandardCharsets;

import org.json.JSONObject;

import io.lumipose.client.json.Json;

/** The characteristics fixtures in src/test/resources/devices/. */
public final class Devices {
    /** Logical multi-camera, focal lengths 2.4 / 4.8 / 9.6 mm, no intrinsic calibration. */
    public static final String LOGICAL = "logical_multi_camera";
    /** Pre-correction array 4080x3060 around a 4000x3000 active array, calibrated, with distortion. */
    public static final String PRE_CORRECTION = "pre_correction_larger";
    /** Front camera at sensor orientation 270 (Mi 8 front sized), no timestamps or sync guarantees. */
    public static final String FRONT_270 = "front_270";
    /** The logical camera without a contrast curve: the sRGB preset (and gamma) only. */
    public static final String PRESET_CURVE_ONLY = "preset_curve_only";

    private Devices() {
    }

    public static JSONObject json(String name) {
        try (InputStream in = Devices.class.getResourceAsStream("/devices/" + name + ".json")) {
            if (in == null) {
                throw new IllegalArgumentException("no fixture devices/" + name + ".json");
            }
            return Json.parseObject(text(in), name);
        } catch (IOException e) {
            throw new IllegalStateException(e);
        }
    }

    public static CameraFacts load(String name) {
        return CameraFacts.fromJson(json(name));
    }

    private static String text(InputStream in) throws IOException {
        java.io.ByteArrayOutputStream out = new java.io.ByteArrayOutputStream();
        byte[] buf = new byte[8192];
        for (int n; (n = in.read(buf)) > 0; ) {
            out.write(buf, 0, n);
        }
        return new String(out.toByteArray(), StandardCharsets.UTF_8);
    }
}
