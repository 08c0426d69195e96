package io.lumipose.client.protocol;

import static org.junit.jupiter.api.Assertions.assertEquals;

import java.util.Arrays;
import java.util.HashSet;
import java.util.Set;

import org.json.JSONObject;
import org.junit.jupiter.api.Test;

import io.lumipose.client.testutil.Repo;

/** The bundled protocol is shared_schemas/capture_protocol.json, field by field. */
class CaptureProtocolTest {
    private static JSONObject file() throws Exception {
        return new JSONObject(Repo.text("shared_schemas/capture_protocol.json"));
    }

    private static long nanos(JSONObject o, String key) {
        return Math.round(o.getDouble(key) * 1e9);
    }

    @Test
    void theLoaderReadsTheSharedFile() throws Exception {
        JSONObject o = file();
        assertEquals(CaptureProtocol.SCHEMA, o.getString("schema"));
        assertEquals(o.getDouble("chip_rate_hz"), CaptureProtocol.CHIP_RATE_HZ);
        assertEquals(o.getInt("message_chips"), CaptureProtocol.MESSAGE_CHIPS);
        assertEquals(o.getDouble("golden_step"), CaptureProtocol.GOLDEN_STEP);
        assertEquals(o.getInt("id_burst_frames"), CaptureProtocol.ID_BURST_FRAMES);
        assertEquals(o.getDouble("id_burst_step"), CaptureProtocol.ID_BURST_STEP);
        assertEquals(nanos(o, "pose_exposure_s"), CaptureProtocol.POSE_EXPOSURE_NS);
        assertEquals(nanos(o, "id_exposure_s"), CaptureProtocol.ID_EXPOSURE_NS);
        assertEquals(nanos(o, "id_max_exposure_s"), CaptureProtocol.ID_MAX_EXPOSURE_NS);
        assertEquals(o.getDouble("id_brightness_fraction"), CaptureProtocol.ID_BRIGHTNESS_FRACTION);
        assertEquals(o.getDouble("window_per_panel"), CaptureProtocol.WINDOW_PER_PANEL);
        assertEquals(o.getInt("window_block_divisor"), CaptureProtocol.WINDOW_BLOCK_DIVISOR);
        assertEquals(o.getDouble("window_min_contrast_dn"), CaptureProtocol.WINDOW_MIN_CONTRAST_DN);
        assertEquals(o.getInt("window_edge_blocks"), CaptureProtocol.WINDOW_EDGE_BLOCKS);
        assertEquals(o.getInt("window_edge_px"), CaptureProtocol.WINDOW_EDGE_PX);
        assertEquals(o.getInt("levels_coarse_short_side_px"), CaptureProtocol.LEVELS_COARSE_SHORT_SIDE_PX);
        assertEquals(o.getDouble("levels_plateau_fraction"), CaptureProtocol.LEVELS_PLATEAU_FRACTION);
    }

    @Test
    void everyKeyOfTheFileIsRead() throws Exception {
        // a key added on the Python side must reach the loader (and this test) too
        Set<String> read = new HashSet<String>(Arrays.asList("schema", "chip_rate_hz", "message_chips",
                "golden_step", "id_burst_frames", "id_burst_step", "pose_exposure_s", "id_exposure_s",
                "id_max_exposure_s", "id_brightness_fraction", "window_per_panel", "window_block_divisor",
                "window_min_contrast_dn", "window_edge_blocks", "window_edge_px", "levels_coarse_short_side_px",
                "levels_plateau_fraction"));
        assertEquals(read, file().keySet());
    }

    @Test
    void theMessagePeriodIsTheChipsAtTheChipRate() throws Exception {
        JSONObject o = file();
        assertEquals(Math.round(o.getInt("message_chips") / o.getDouble("chip_rate_hz") * 1e9),
                CaptureProtocol.messagePeriodNs());
    }
}
