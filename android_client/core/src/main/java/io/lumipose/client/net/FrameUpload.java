package io.lumipose.client.net;

import io.lumipose.client.frame.FrameMeta;

/**
 * One frame ready to send: its packed Y8 pixels (the window, or the whole plane) and its JSON.
 * The array is handed over, not copied: nobody writes to it after it is queued.
 */
public final class FrameUpload {
    public final FrameMeta meta;
    final byte[] luma;

    public FrameUpload(byte[] luma, FrameMeta meta) {
        if (luma.length != meta.frameBytes()) {
            throw new IllegalArgumentException("frame bytes: " + luma.length + " given, row_stride * height = "
                    + meta.frameBytes());
        }
        this.luma = luma;
        this.meta = meta;
    }

    /** Bytes on the wire (before any compression). */
    public int bytes() {
        return luma.length;
    }

    /** True for an ID frame (the contract reads a missing frame_kind as pose). */
    public boolean isId() {
        return "id".equals(meta.frameKind);
    }
}
