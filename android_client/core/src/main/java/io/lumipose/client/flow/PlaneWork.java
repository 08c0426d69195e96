package io.lumipose.client.flow;

import java.nio.ByteBuffer;

import io.lumipose.client.frame.BeaconWindow;
import io.lumipose.client.frame.FrameLevels;
import io.lumipose.client.frame.LumaPlane;
import io.lumipose.client.frame.Window;

/**
 * The pixel work {@link FramePipeline} does on a frame: the costly part (a 20-megapixel plane takes
 * tens of ms), which a burst the uploader cannot take must not pay. One interface so that a test
 * can count it; the app always runs {@link #PIXELS}.
 */
interface PlaneWork {
    /** {@link BeaconWindow#find}: the panel's window, or null when none stands out. */
    Window findPanel(ByteBuffer plane, int width, int height, int rowStride, int pixelStride);

    /** {@link LumaPlane#copyWindow}: the window's pixels, packed. */
    byte[] copyWindow(ByteBuffer plane, int width, int height, int rowStride, int pixelStride, Window w);

    /** {@link FrameLevels#measure}: the whole plane's [background, plateau]. */
    double[] levels(ByteBuffer plane, int width, int height, int rowStride, int pixelStride);

    /** The real work. */
    PlaneWork PIXELS = new PlaneWork() {
        @Override
        public Window findPanel(ByteBuffer plane, int width, int height, int rowStride, int pixelStride) {
            return BeaconWindow.find(plane, width, height, rowStride, pixelStride);
        }

        @Override
        public byte[] copyWindow(ByteBuffer plane, int width, int height, int rowStride, int pixelStride,
                                 Window w) {
            return LumaPlane.copyWindow(plane, width, height, rowStride, pixelStride, w);
        }

        @Override
        public double[] levels(ByteBuffer plane, int width, int height, int rowStride, int pixelStride) {
            return FrameLevels.measure(plane, width, height, rowStride, pixelStride);
        }
    };
}
