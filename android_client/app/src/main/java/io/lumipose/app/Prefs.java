package io.lumipose.app;

import android.content.Context;
import android.content.SharedPreferences;
import android.os.Build;

import io.lumipose.client.capture.CaptureSettingsChooser;
import io.lumipose.client.net.ClientConfig;
import io.lumipose.client.net.RetryPolicy;
import java.util.UUID;

/** The settings screen's values, kept in SharedPreferences. */
final class Prefs {
    static final String SERVER_URL = "server_url";
    static final String API_KEY = "api_key";
    static final String CAMERA_ID = "camera_id";
    static final String MAP_NAME = "map_name";
    static final String FOCUS_DISTANCE_M = "focus_distance_m";
    static final String MAX_MEGAPIXELS = "max_megapixels";
    static final String ID_EXPOSURE_US = "id_exposure_us";
    static final String BENCH_INDEX = "bench_index";
    static final String READ_IDS = "read_ids";
    static final String MAP_X_BEARING_DEG = "map_x_bearing_deg";
    static final String INSTALL_ID = "install_id";

    private final SharedPreferences p;

    Prefs(Context context) {
        p = context.getSharedPreferences("lumipose", Context.MODE_PRIVATE);
    }

    String serverUrl() {
        return p.getString(SERVER_URL, "http://192.168.1.10:8000");
    }

    String apiKey() {
        return p.getString(API_KEY, "");
    }

    /** Empty: the first back camera with MANUAL_SENSOR. */
    String cameraId() {
        return p.getString(CAMERA_ID, "");
    }

    String mapName() {
        return p.getString(MAP_NAME, "test-bench");
    }

    float focusDistanceM() {
        return p.getFloat(FOCUS_DISTANCE_M, 1.0f);
    }

    float maxMegapixels() {
        return p.getFloat(MAX_MEGAPIXELS, 2.1f);
    }

    long idExposureNs() {
        return p.getLong(ID_EXPOSURE_US, CaptureSettingsChooser.DEFAULT_ID_EXPOSURE_NS / 1000) * 1000;
    }

    /** Interleave beacon-ID frames in live mode (rooms with several panels). */
    boolean readIds() {
        return p.getBoolean(READ_IDS, true);
    }

    /** Compass bearing of the map's +X axis (deg clockwise from north); null when not set: no heading is sent. */
    Double mapXBearingDeg() {
        String v = p.getString(MAP_X_BEARING_DEG, "").trim();
        if (v.isEmpty()) {
            return null;
        }
        try {
            return Double.valueOf(v);
        } catch (NumberFormatException e) {
            return null;
        }
    }

    int benchIndex() {
        return p.getInt(BENCH_INDEX, 0);
    }

    void setBenchIndex(int index) {
        p.edit().putInt(BENCH_INDEX, index).apply();
    }

    SharedPreferences.Editor edit() {
        return p.edit();
    }

    /** @throws IllegalArgumentException with a readable message for a bad server URL */
    ClientConfig clientConfig() {
        return new ClientConfig(serverUrl(), apiKey(), deviceId(), true, RetryPolicy.defaults());
    }

    /**
     * X-Lumipose-Device: the server keeps one tracking session per value, so two phones of the same
     * model must differ; a random id made once per installation, after the model for the logs.
     */
    String deviceId() {
        String id = p.getString(INSTALL_ID, null);
        if (id == null) {
            id = UUID.randomUUID().toString().substring(0, 8);
            p.edit().putString(INSTALL_ID, id).apply();
        }
        return Build.MANUFACTURER + " " + Build.MODEL + " " + id;
    }
}
