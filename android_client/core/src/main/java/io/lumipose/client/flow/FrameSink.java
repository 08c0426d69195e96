package io.lumipose.client.flow;

import java.nio.ByteBuffer;

import io.lumipose.client.camera.FrameResult;

/**
 * Where a camera (the app's Camera2 controller, or the replay camera in tests) hands each frame:
 * its capture result and its Y plane arrive separately, in either order, matched by
 * SENSOR_TIMESTAMP. Both calls come on the camera's one thread.
 */
public interface FrameSink {
    /** The frame's TotalCaptureResult, read into the core's terms. */
    void onResult(FrameResult result);

    /**
     * The frame's Y plane, valid only during the call (the camera reuses the buffer): the sink
     * copies what it keeps. Rows start {@code rowStride} bytes apart, samples {@code pixelStride}.
     */
    void onImage(long timestampNs, ByteBuffer yPlane, int width, int height, int rowStride, int pixelStride);
}
