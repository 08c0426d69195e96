package io.lumipose.client.frame;

import static org.junit.jupiter.api.Assertions.assertArrayEquals;
import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertNull;
import static org.junit.jupiter.api.Assertions.assertTrue;

import java.nio.ByteBuffer;
import java.nio.charset.StandardCharsets;
import java.nio.file.Files;
import java.nio.file.Path;
import java.util.Iterator;

import org.json.JSONArray;
import org.json.JSONObject;
import org.junit.jupiter.api.Test;
import org.junit.jupiter.api.io.TempDir;

import io.lumipose.client.testutil.Python;

class BeaconWindowTest {
    /**
     * crop.py's beacon_window and windows.py's frame_levels, and their ports, on the same pixels:
     * rendered test-bench frames at 1-3 m (1080 wide and the full 20 MP), the bench fixture and
     * the edge cases of crop.py's tests.
     */
    @Test
    void sameWindowAsThePythonClientOnTheSamePixels(@TempDir Path dir) throws Exception {
        Python.run("frame/beacon_windows.py", dir.toString());
        JSONObject expected = new JSONObject(new String(Files.readAllBytes(dir.resolve("windows.json")),
                StandardCharsets.UTF_8));
        assertTrue(expected.length() >= 10);
        Iterator<String> names = expected.keys();
        while (names.hasNext()) {
            String name = names.next();
            JSONObject e = expected.getJSONObject(name);
            int width = e.getInt("width");
            int height = e.getInt("height");
            byte[] packed = Files.readAllBytes(dir.resolve(name + ".y"));
            Window want = e.isNull("window") ? null : window(e.getJSONArray("window"));
            assertEquals(want, BeaconWindow.find(packed, width, height), name);
            // as a camera hands it over: padded rows, the plane at an offset in its buffer
            assertEquals(want, BeaconWindow.find(padded(packed, width, height, width + 64, 16), width, height,
                    width + 64, 1), name + " (padded)");
            JSONArray levels = e.getJSONArray("levels");
            double[] wantLevels = {levels.getDouble(0), levels.getDouble(1)};
            assertArrayEquals(wantLevels, FrameLevels.measure(padded(packed, width, height, width + 64, 16), width,
                    height, width + 64, 1), 0, name + ": levels as shared_schemas/windows.py measures them");
        }
    }

    @Test
    void pixelStrideAboveOneReadsTheSameSamples() {
        int width = 240;
        int height = 180;
        byte[] packed = new byte[width * height];
        for (int y = 100; y < 130; y++) {
            for (int x = 50; x < 80; x++) {
                packed[y * width + x] = (byte) 220;
            }
        }
        ByteBuffer strided = ByteBuffer.allocate(height * width * 2);
        for (int i = 0; i < packed.length; i++) {
            strided.put(i * 2, packed[i]);
        }
        Window w = BeaconWindow.find(packed, width, height);
        assertEquals(w, BeaconWindow.find(strided, width, height, width * 2, 2));
        assertArrayEquals(LumaPlane.copyWindow(ByteBuffer.wrap(packed), width, height, width, 1, w),
                LumaPlane.copyWindow(strided, width, height, width * 2, 2, w));
    }

    @Test
    void aDarkFrameHasNoWindow() {
        assertNull(BeaconWindow.find(new byte[640 * 480], 640, 480));
    }

    private static Window window(JSONArray a) {
        return new Window(a.getInt(0), a.getInt(1), a.getInt(2), a.getInt(3));
    }

    static ByteBuffer padded(byte[] packed, int width, int height, int rowStride, int offset) {
        ByteBuffer b = ByteBuffer.allocateDirect(offset + (height - 1) * rowStride + width);
        for (int row = 0; row < height; row++) {
            b.position(offset + row * rowStride);
            b.put(packed, row * width, width);
        }
        b.position(offset);
        return b;
    }
}
