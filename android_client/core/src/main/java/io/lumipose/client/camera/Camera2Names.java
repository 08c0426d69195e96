package io.lumipose.client.camera;

import java.util.ArrayList;
import java.util.List;

/**
 * Camera2's integer enums as the lower-case names CameraFacts and FrameResult JSON use
 * (docs/android.md). The values are Camera2's public constants; an unknown value (a newer
 * Android, a vendor extension) keeps its number, so nothing is silently mistaken for another mode.
 */
public final class Camera2Names {
    private static final String[] LENS_FACING = {"front", "back", "external"};
    private static final String[] CAPABILITIES = {"backward_compatible", "manual_sensor", "manual_post_processing",
            "raw", "private_reprocessing", "read_sensor_settings", "burst_capture", "yuv_reprocessing", "depth_output",
            "constrained_high_speed_video", "motion_tracking", "logical_multi_camera", "monochrome",
            "secure_image_data", "system_camera", "offline_processing"};
    private static final String[] TIMESTAMP_SOURCE = {"unknown", "realtime"};
    private static final String[] FOCUS_CALIBRATION = {"uncalibrated", "approximate", "calibrated"};
    private static final String[] OIS = {"off", "on"};
    private static final String[] TONEMAP = {"contrast_curve", "fast", "high_quality", "gamma_value", "preset_curve"};
    private static final String[] TONEMAP_PRESET = {"srgb", "rec709"};
    private static final String[] EDGE = {"off", "fast", "high_quality", "zero_shutter_lag"};
    private static final String[] NOISE_REDUCTION = {"off", "fast", "high_quality", "minimal", "zero_shutter_lag"};
    private static final String[] DISTORTION_CORRECTION = {"off", "fast", "high_quality"};
    private static final String[] ROTATE_AND_CROP = {"none", "90", "180", "270", "auto"};

    /*
     * The int-array keys' tables as Namers for names(int[], Namer). Plain objects rather than method
     * references: the app is dexed by dx, which does not desugar, and Android has no usable
     * LambdaMetafactory (docs/android.md, "Dex and API level checks"). Declared after the tables they read.
     */
    public static final Namer CAPABILITY = new Table(CAPABILITIES);
    public static final Namer OIS_MODE = new Table(OIS);
    public static final Namer TONEMAP_MODE = new Table(TONEMAP);
    public static final Namer EDGE_MODE = new Table(EDGE);
    public static final Namer NOISE_REDUCTION_MODE = new Table(NOISE_REDUCTION);
    public static final Namer DISTORTION_CORRECTION_MODE = new Table(DISTORTION_CORRECTION);
    public static final Namer ROTATE_AND_CROP_MODE = new Table(ROTATE_AND_CROP);

    private Camera2Names() {
    }

    public static String lensFacing(int v) {
        return name(LENS_FACING, v);
    }

    public static String capability(int v) {
        return name(CAPABILITIES, v);
    }

    public static String timestampSource(int v) {
        return name(TIMESTAMP_SOURCE, v);
    }

    public static String focusDistanceCalibration(int v) {
        return name(FOCUS_CALIBRATION, v);
    }

    public static String oisMode(int v) {
        return name(OIS, v);
    }

    public static String tonemapMode(int v) {
        return name(TONEMAP, v);
    }

    /** {@code TONEMAP_PRESET_CURVE}: "srgb", "rec709". */
    public static String tonemapPresetCurve(int v) {
        return name(TONEMAP_PRESET, v);
    }

    public static String edgeMode(int v) {
        return name(EDGE, v);
    }

    public static String noiseReductionMode(int v) {
        return name(NOISE_REDUCTION, v);
    }

    public static String distortionCorrectionMode(int v) {
        return name(DISTORTION_CORRECTION, v);
    }

    public static String rotateAndCrop(int v) {
        return name(ROTATE_AND_CROP, v);
    }

    /** {@code SYNC_MAX_LATENCY}: -1 unknown, 0 per-frame control, else a frame count (CameraFacts' encoding). */
    public static int syncMaxLatency(int v) {
        return v < 0 ? CameraFacts.SYNC_UNKNOWN : v;
    }

    /** Each value of a Camera2 int array through {@code names}; null stays null (the key is absent). */
    public static List<String> names(int[] values, Namer names) {
        if (values == null) {
            return null;
        }
        List<String> out = new ArrayList<String>();
        for (int v : values) {
            out.add(names.name(v));
        }
        return out;
    }

    /** One of the enum tables above, e.g. {@link #CAPABILITY}. */
    public interface Namer {
        String name(int value);
    }

    private static final class Table implements Namer {
        private final String[] table;

        Table(String[] table) {
            this.table = table;
        }

        @Override
        public String name(int value) {
            return Camera2Names.name(table, value);
        }
    }

    private static String name(String[] table, int v) {
        return v >= 0 && v < table.length ? table[v] : String.valueOf(v);
    }
}
