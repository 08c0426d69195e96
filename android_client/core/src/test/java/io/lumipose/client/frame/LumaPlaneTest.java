package io.lumipose.client.frame;

import static org.junit.jupiter.api.Assertions.assertArrayEquals;
import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertThrows;
import static org.junit.jupiter.api.Assertions.assertTrue;

import java.nio.ByteBuffer;

import org.junit.jupiter.api.Test;

class LumaPlaneTest {
    /** A plane of width x height samples (value = 10 * row + col) padded to rowStride, last row unpadded. */
    private static ByteBuffer plane(int width, int height, int rowStride, int pixelStride, boolean padLastRow) {
        int size = (height - 1) * rowStride + (padLastRow ? rowStride : (width - 1) * pixelStride + 1);
        byte[] data = new byte[size];
        java.util.Arrays.fill(data, (byte) 0xEE);
        for (int r = 0; r < height; r++) {
            for (int c = 0; c < width; c++) {
                data[r * rowStride + c * pixelStride] = (byte) (10 * r + c);
            }
        }
        return ByteBuffer.wrap(data);
    }

    private static byte[] expected(int width, int height) {
        byte[] out = new byte[width * height];
        for (int r = 0; r < height; r++) {
            for (int c = 0; c < width; c++) {
                out[r * width + c] = (byte) (10 * r + c);
            }
        }
        return out;
    }

    @Test
    void rowStrideIsRemovedAndTheLastRowMayLackPadding() {
        ByteBuffer b = plane(5, 4, 8, 1, false);
        assertEquals(3 * 8 + 5, b.remaining());
        assertArrayEquals(expected(5, 4), LumaPlane.copy(b, 5, 4, 8, 1));
        assertArrayEquals(expected(5, 4), LumaPlane.copy(plane(5, 4, 8, 1, true), 5, 4, 8, 1));
    }

    @Test
    void packedPlaneIsCopiedAsIs() {
        assertArrayEquals(expected(6, 3), LumaPlane.copy(plane(6, 3, 6, 1, true), 6, 3, 6, 1));
    }

    @Test
    void pixelStrideAboveOneIsHonoured() {
        assertArrayEquals(expected(4, 3), LumaPlane.copy(plane(4, 3, 10, 2, false), 4, 3, 10, 2));
    }

    @Test
    void bufferPositionIsUsedAndLeftAlone() {
        ByteBuffer inner = plane(5, 4, 8, 1, false);
        ByteBuffer b = ByteBuffer.allocate(inner.remaining() + 3);
        b.put(new byte[] {1, 2, 3}).put(inner);
        b.position(3);
        assertArrayEquals(expected(5, 4), LumaPlane.copy(b, 5, 4, 8, 1));
        assertEquals(3, b.position());
    }

    @Test
    void shortBufferIsRejectedWithTheNumbers() {
        ByteBuffer b = plane(5, 4, 8, 1, false);
        b.limit(b.limit() - 1);
        IllegalArgumentException e = assertThrows(IllegalArgumentException.class, () -> LumaPlane.copy(b, 5, 4, 8, 1));
        assertTrue(e.getMessage().contains("row_stride 8"), e.getMessage());
        assertThrows(IllegalArgumentException.class, () -> LumaPlane.copy(plane(5, 4, 8, 1, true), 5, 4, 4, 1));
        assertThrows(IllegalArgumentException.class, () -> LumaPlane.copy(plane(5, 4, 8, 1, true), 0, 4, 8, 1));
    }
}
