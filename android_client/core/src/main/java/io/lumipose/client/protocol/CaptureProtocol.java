package io.lumipose.client.protocol;

import java.io.ByteArrayOutputStream;
import java.io.IOException;
import java.io.InputStream;

import org.json.JSONObject;

import io.lumipose.client.json.Json;

/**
 * The capture protocol shared with the server, read once from the classpath resource
 * {@value #RESOURCE}: a copy of {@code shared_schemas/capture_protocol.json}, which the Python side
 * writes from the constants the server and the Python client use ({@code python -m
 * lumipose_cli.capture_protocol}). Nothing here is typed in by hand, so the app cannot drift from
 * the server's codec, burst and exposure limit, nor from the client's beacon-window rule.
 */
public final class CaptureProtocol {
    public static final String RESOURCE = "/io/lumipose/client/protocol/capture_protocol.json";
    public static final String SCHEMA = "lumipose.capture_protocol/1";

    private static final JSONObject FILE = load();

    /** The beacons' chip rate, Hz, and the chips of one repeating message. */
    public static final double CHIP_RATE_HZ = number("chip_rate_hz");
    public static final int MESSAGE_CHIPS = integer("message_chips");
    /** (3 - sqrt 5) / 2: the message-phase step between captures that spreads their bursts most evenly. */
    public static final double GOLDEN_STEP = number("golden_step");
    /** ID frames after each pose frame, each this fraction of a message later in the message. */
    public static final int ID_BURST_FRAMES = integer("id_burst_frames");
    public static final double ID_BURST_STEP = number("id_burst_step");
    /** Pose frames' exposure (the paper's 10 ms), ID frames' default, the longest ID exposure the server reads. */
    public static final long POSE_EXPOSURE_NS = nanos("pose_exposure_s");
    public static final long ID_EXPOSURE_NS = nanos("id_exposure_s");
    public static final long ID_MAX_EXPOSURE_NS = nanos("id_max_exposure_s");
    /** ID-frame brightness (exposure x ISO) as a share of the pose frame's: the pose frame's panel clips ~4x over. */
    public static final double ID_BRIGHTNESS_FRACTION = number("id_brightness_fraction");
    /** The beacon window's rule (lumipose_client/crop.py): window size per panel extent, coarse-view blocks, ... */
    public static final double WINDOW_PER_PANEL = number("window_per_panel");
    public static final int WINDOW_BLOCK_DIVISOR = integer("window_block_divisor");
    public static final double WINDOW_MIN_CONTRAST_DN = number("window_min_contrast_dn");
    public static final int WINDOW_EDGE_BLOCKS = integer("window_edge_blocks");
    /** ... and the pixels the window grows by beyond those blocks: the server's own margin around the panel. */
    public static final int WINDOW_EDGE_PX = integer("window_edge_px");
    /** The whole frame's levels sent with a window (shared_schemas/windows.py, {@code FrameLevels}). */
    public static final int LEVELS_COARSE_SHORT_SIDE_PX = integer("levels_coarse_short_side_px");
    public static final double LEVELS_PLATEAU_FRACTION = number("levels_plateau_fraction");

    private CaptureProtocol() {
    }

    /** One message: {@link #MESSAGE_CHIPS} chips at {@link #CHIP_RATE_HZ} (8.4 ms). */
    public static long messagePeriodNs() {
        return Math.round(MESSAGE_CHIPS / CHIP_RATE_HZ * 1e9);
    }

    private static double number(String key) {
        return Json.requireDouble(FILE, key, key);
    }

    private static int integer(String key) {
        return Json.requireInt(FILE, key, key);
    }

    private static long nanos(String secondsKey) {
        return Math.round(number(secondsKey) * 1e9);
    }

    private static JSONObject load() {
        InputStream in = CaptureProtocol.class.getResourceAsStream(RESOURCE);
        if (in == null) {
            throw new IllegalStateException("the build did not bundle " + RESOURCE
                    + " (shared_schemas/capture_protocol.json)");
        }
        try {
            try {
                ByteArrayOutputStream bytes = new ByteArrayOutputStream();
                byte[] buffer = new byte[4096];
                for (int n = in.read(buffer); n >= 0; n = in.read(buffer)) {
                    bytes.write(buffer, 0, n);
                }
                JSONObject o = Json.parseObject(bytes.toString("UTF-8"), RESOURCE);
                Json.checkSchema(o, SCHEMA);
                return o;
            } finally {
                in.close();
            }
        } catch (IOException e) {
            throw new IllegalStateException("cannot read " + RESOURCE, e);
        }
    }
}
