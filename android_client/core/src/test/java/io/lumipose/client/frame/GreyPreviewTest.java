package io.lumipose.client.frame;

import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertThrows;

import java.nio.ByteBuffer;

import org.junit.jupiter.api.Test;

class GreyPreviewTest {
    @Test
    void everyStepthSampleOfAPaddedPlane() {
        int w = 1000;
        int h = 600;
        int stride = 1024;
        byte[] plane = new byte[(h - 1) * stride + w];
        for (int y = 0; y < h; y++) {
            for (int x = 0; x < w; x++) {
                plane[y * stride + x] = (byte) ((x / 4 + y) & 0xff);
            }
        }
        GreyPreview p = GreyPreview.of(ByteBuffer.wrap(plane), w, h, stride, 1, 320);
        assertEquals(4, p.step, "the smallest step that fits 1000 px in 320");
        assertEquals(250, p.width);
        assertEquals(150, p.height);
        int[] argb = p.argb();
        int v = (100 + 4 * 20) & 0xff; // preview (100, 20) is frame (400, 80)
        assertEquals(0xff000000 | v << 16 | v << 8 | v, argb[20 * 250 + 100]);
        assertEquals(400.0, p.toFrameX(100), 0.0);
        assertEquals(80.0, p.toFrameY(20), 0.0);
        assertEquals(999.0, p.toFrameX(400), 0.0, "clamped to the frame");
    }

    @Test
    void meanLevelAndBadSizes() {
        byte[] grey = new byte[64 * 48];
        java.util.Arrays.fill(grey, (byte) 200);
        assertEquals(200.0, GreyPreview.of(ByteBuffer.wrap(grey), 64, 48, 64, 1, 320).meanDn(), 0.0);
        assertThrows(IllegalArgumentException.class, () -> GreyPreview.of(ByteBuffer.wrap(grey), 64, 48, 64, 1, 0));
        assertThrows(IllegalArgumentException.class, () -> GreyPreview.of(ByteBuffer.wrap(grey), 64, 49, 64, 1, 32));
    }
}
