package io.lumipose.client.flow;

import java.nio.ByteBuffer;
import java.util.Iterator;
import java.util.LinkedHashMap;
import java.util.concurrent.Executor;
import java.util.concurrent.RejectedExecutionException;

import io.lumipose.client.camera.FrameResult;
import io.lumipose.client.capture.FrameDescriber;
import io.lumipose.client.capture.RequestSpec;
import io.lumipose.client.frame.FrameMeta;
import io.lumipose.client.frame.GreyPreview;
import io.lumipose.client.frame.LumaPlane;
import io.lumipose.client.sensor.GravityHistory;
import io.lumipose.client.sensor.GyroHistory;

/**
 * The shutter of the calibration and survey screens: a {@link FrameSink} that, once {@link #arm}ed,
 * takes the next pose frame the {@link FrameDescriber} keeps (described exactly as a positioning
 * frame, with the attitude and rate at its timestamp) as a whole photo, not a window, and hands it
 * to the listener on the executor. Between shots it keeps nothing but a small {@link GreyPreview}
 * every {@code previewEveryNs}, so the screen shows what the camera sees.
 *
 * <p>Camera calls come on the camera's one thread; {@link #arm} and {@link #close} from any.
 */
public final class StillCapture implements FrameSink {
    /** What the shutter tells the screen. */
    public interface Listener {
        /** The photo taken: packed Y8 (row_stride = width) and its JSON. On the executor. */
        void onPhoto(byte[] luma, FrameMeta meta);

        /** A small picture of the latest frame. On the camera's thread. */
        void onPreview(GreyPreview preview);

        /** An armed shot passed over a frame, and why (it waits for the next). On the camera's thread. */
        void onDropped(String reason);
    }

    /** The preview's longer side, px. */
    public static final int PREVIEW_SIDE = 320;
    /** Results or copied planes waiting for their other half while armed (planes are megabytes). */
    private static final int MAX_UNMATCHED = 3;

    private final FrameDescriber describer;
    private final GravityHistory attitude;
    private final GyroHistory rates;
    private final boolean timestampsRealtime;
    private final Executor executor;
    private final Listener listener;
    private final long previewEveryNs;

    private boolean armed;
    private boolean closed;
    private long lastPreviewNs = Long.MIN_VALUE;
    private final LinkedHashMap<Long, FrameResult> results = new LinkedHashMap<Long, FrameResult>();
    private final LinkedHashMap<Long, byte[]> planes = new LinkedHashMap<Long, byte[]>();
    private final LinkedHashMap<Long, int[]> sizes = new LinkedHashMap<Long, int[]>();

    public StillCapture(FrameDescriber describer, GravityHistory attitude, GyroHistory rates,
                        boolean timestampsRealtime, Executor executor, Listener listener, long previewEveryNs) {
        this.describer = describer;
        this.attitude = attitude;
        this.rates = rates;
        this.timestampsRealtime = timestampsRealtime;
        this.executor = executor;
        this.listener = listener;
        this.previewEveryNs = previewEveryNs;
    }

    /** Takes the next pose frame the describer keeps; false when a shot is already waiting or closed. */
    public synchronized boolean arm() {
        if (armed || closed) {
            return false;
        }
        armed = true;
        return true;
    }

    /** True while a shot waits for its frame. */
    public synchronized boolean armed() {
        return armed;
    }

    /** Ignores every later frame and forgets what waits. Any thread. */
    public synchronized void close() {
        closed = true;
        armed = false;
        forget();
    }

    @Override
    public synchronized void onResult(FrameResult result) {
        if (!armed) {
            return;
        }
        byte[] plane = planes.remove(result.timestampNs);
        if (plane != null) {
            take(result, plane, sizes.remove(result.timestampNs));
            return;
        }
        results.put(result.timestampNs, result);
        evict(results);
    }

    @Override
    public synchronized void onImage(long timestampNs, ByteBuffer yPlane, int width, int height, int rowStride,
                                     int pixelStride) {
        if (closed) {
            return;
        }
        if (previewEveryNs <= 0 || lastPreviewNs == Long.MIN_VALUE || timestampNs - lastPreviewNs >= previewEveryNs) {
            lastPreviewNs = timestampNs;
            listener.onPreview(GreyPreview.of(yPlane, width, height, rowStride, pixelStride, PREVIEW_SIDE));
        }
        if (!armed) {
            return;
        }
        byte[] plane = LumaPlane.copy(yPlane, width, height, rowStride, pixelStride);
        int[] size = {width, height};
        FrameResult result = results.remove(timestampNs);
        if (result != null) {
            take(result, plane, size);
            return;
        }
        planes.put(timestampNs, plane);
        sizes.put(timestampNs, size);
        evict(planes);
        evict(sizes);
    }

    /** A matched frame: described as any positioning frame; the first pose frame kept is the photo. */
    private void take(FrameResult result, byte[] plane, int[] size) {
        GravityHistory.Attitude a = attitude.forFrame(result.timestampNs, timestampsRealtime);
        float[] rate = rates.forFrame(result.timestampNs, FramePipeline.readoutEndNs(result), timestampsRealtime);
        FrameDescriber.Described d = describer.describe(result, a.gravity, a.rotationToEnu, rate);
        if (d.meta == null) {
            listener.onDropped(d.dropReason);
            return;
        }
        if (!RequestSpec.POSE.equals(d.kind)) {
            listener.onDropped("an ID frame, not a photo");
            return;
        }
        if (d.meta.width != size[0] || d.meta.height != size[1]) {
            listener.onDropped("image " + size[0] + "x" + size[1] + " is not the planned " + d.meta.width + "x"
                    + d.meta.height);
            return;
        }
        armed = false;
        forget();
        final byte[] luma = plane;
        final FrameMeta meta = d.meta;
        try {
            executor.execute(new Runnable() {
                @Override
                public void run() {
                    listener.onPhoto(luma, meta);
                }
            });
        } catch (RejectedExecutionException e) {
            listener.onDropped("screen closed before the photo went");
        }
    }

    private void forget() {
        results.clear();
        planes.clear();
        sizes.clear();
    }

    private static <V> void evict(LinkedHashMap<Long, V> waiting) {
        Iterator<Long> it = waiting.keySet().iterator();
        while (waiting.size() > MAX_UNMATCHED) {
            it.next();
            it.remove();
        }
    }
}
