package io.lumipose.app;

import android.content.Context;
import android.content.SharedPreferences;
import android.os.Build;

import java.util.UUID;

import io.lumipose.client.calibration.BoardSpec;
import io.lumipose.client.camera.DeviceProfile;
import io.lumipose.client.map.Beacon;
import io.lumipose.client.map.RoomMap;
import io.lumipose.client.net.ClientConfig;
import io.lumipose.client.net.RetryPolicy;
import io.lumipose.client.protocol.CaptureProtocol;

/** The settings screen's values, kept in SharedPreferences. */
final class Prefs {
    static final String SERVER_URL = "server_url";
    static final String API_KEY = "api_key";
    static final String CAMERA_ID = "camera_id";
    static final String MAP_NAME = "map_name";
    static final String HAND_HEIGHT_M = "hand_height_m";
    static final String MAX_MEGAPIXELS = "max_megapixels";
    static final String ID_EXPOSURE_US = "id_exposure_us";
    static final String BENCH_INDEX = "bench_index";
    static final String READ_IDS = "read_ids";
    static final String MAP_X_BEARING_DEG = "map_x_bearing_deg";
    static final String INSTALL_ID = "install_id";
    static final String BOARD_SPEC = "board_spec";
    /** Followed by the camera id: each camera has its own calibration. */
    static final String CALIBRATED_PROFILE = "calibrated_profile:";
    /**
     * A 7 x 5 board of 30 mm squares and 22 mm markers until the user pastes the board.json that
     * {@code lumipose calibrate board} wrote beside the printed board (the screen edits it).
     */
    static final String DEFAULT_BOARD_SPEC = "{\"schema\": \"lumipose.board/1\", \"squares_x\": 7, \"squares_y\": 5, "
            + "\"square_m\": 0.03, \"marker_m\": 0.022, \"dictionary\": \"DICT_5X5_100\"}";

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

    /** Height of the phone above the floor while in use, m (a hand at chest height by default). */
    float handHeightM() {
        return p.getFloat(HAND_HEIGHT_M, 1.3f);
    }

    /**
     * Distance from the camera up to the panels, m, where the camera focuses: the map's ceiling
     * (its highest panel) minus the hand's height. A map whose panels hang lower than that (less
     * than 0.3 m above the hand) is a bench's, measured from the phone's own plane: the ceiling
     * height itself, then.
     */
    double ceilingDistanceM(RoomMap map) {
        double ceiling = 0;
        for (Beacon b : map.beacons) {
            ceiling = Math.max(ceiling, b.centerM()[2]);
        }
        double aboveHand = ceiling - handHeightM();
        return aboveHand >= 0.3 ? aboveHand : Math.max(0.3, ceiling);
    }

    float maxMegapixels() {
        return p.getFloat(MAX_MEGAPIXELS, 2.1f);
    }

    long idExposureNs() {
        return p.getLong(ID_EXPOSURE_US, CaptureProtocol.ID_EXPOSURE_NS / 1000) * 1000;
    }

    /** Interleave beacon-ID frames in live mode (rooms with several panels). */
    boolean readIds() {
        return p.getBoolean(READ_IDS, true);
    }

    /**
     * Compass bearing of the map's +X axis (deg clockwise from north) as typed; the map's own
     * {@code bearing_deg} wins when it has one. Null when not set: then no heading is sent.
     */
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

    /** The board.json of the printed board (as text: the screen shows and edits it). */
    String boardSpecJson() {
        return p.getString(BOARD_SPEC, DEFAULT_BOARD_SPEC);
    }

    /**
     * Reads the board spec the user gave and keeps it for next time.
     *
     * @throws IllegalArgumentException naming the field when the text is not a board spec
     */
    BoardSpec saveBoardSpec(String json) {
        BoardSpec spec = BoardSpec.fromJson(json);
        p.edit().putString(BOARD_SPEC, json).apply();
        return spec;
    }

    /**
     * The calibrated profile of camera {@code cameraId}, or null: none, or one this version cannot
     * read (then the frames go with Camera2's intrinsics, as before the calibration).
     */
    DeviceProfile calibratedProfile(String cameraId) {
        String json = p.getString(CALIBRATED_PROFILE + cameraId, null);
        if (json == null) {
            return null;
        }
        try {
            return DeviceProfile.fromJson(json);
        } catch (IllegalArgumentException e) {
            return null;
        }
    }

    void setCalibratedProfile(String cameraId, DeviceProfile profile) {
        p.edit().putString(CALIBRATED_PROFILE + cameraId, profile.toJson().toString()).apply();
    }

    void setMapName(String name) {
        p.edit().putString(MAP_NAME, name).apply();
    }

    /** A profile id for this phone's camera (the calibrated one is "<this>-calibrated"). */
    String phoneProfileId(String cameraId) {
        return DeviceProfile.safeId(Build.MANUFACTURER + "-" + Build.MODEL + "-camera" + cameraId);
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

    /**
     * Map fetches and the other reads: retries and a patient timeout; stored samples and surveys go
     * once with a long one (the client's rule); no gzip (it costs more than it saves on a LAN), frames
     * located in the map the app draws.
     *
     * @throws IllegalArgumentException with a readable message for a bad server URL
     */
    ClientConfig clientConfig() {
        return new ClientConfig(serverUrl(), apiKey(), deviceId(), false, RetryPolicy.defaults()).withMap(mapName());
    }

    /** Live frames: one attempt, a short read timeout, in the map the app draws. */
    ClientConfig liveConfig() {
        return ClientConfig.live(serverUrl(), apiKey(), deviceId(), mapName());
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
