package io.lumipose.app.camera;

import android.media.Image;
import android.media.ImageReader;
import android.os.Handler;

import java.util.ArrayDeque;
import java.util.Deque;

import org.robolectric.annotation.Implementation;
import org.robolectric.annotation.Implements;
import org.robolectric.annotation.RealObject;
import org.robolectric.annotation.Resetter;
import org.robolectric.shadows.ShadowImageReader;

/**
 * Robolectric's ImageReader makes images only from what is drawn on its surface (RGBA): this one
 * hands out the YUV_420_888 images {@link FakeCamera} queues, to the listener the app set, on the
 * app's handler, as the camera's buffer queue would. Counts what the app closes.
 */
@Implements(ImageReader.class)
public class ShadowYuvImageReader extends ShadowImageReader {
    private static volatile ShadowYuvImageReader latest;

    @RealObject
    private ImageReader reader;
    private final Deque<Image> queued = new ArrayDeque<Image>();
    private final java.util.List<Image> held = new java.util.ArrayList<Image>();
    private ImageReader.OnImageAvailableListener listener;
    private Handler handler;
    private int acquired;

    @Implementation
    protected void setOnImageAvailableListener(ImageReader.OnImageAvailableListener listener, Handler handler) {
        synchronized (this) {
            this.listener = listener;
            this.handler = handler;
        }
        latest = this;
    }

    /** As the real reader: at most maxImages held (acquired, not closed) at once, else it throws. */
    @Implementation
    protected Image acquireNextImage() {
        synchronized (this) {
            int open = 0;
            for (Image i : held) {
                open += i instanceof YuvImage && ((YuvImage) i).closed() ? 0 : 1;
            }
            if (open >= reader.getMaxImages()) {
                throw new IllegalStateException("maxImages (" + reader.getMaxImages() + ") has already been acquired, "
                        + "call #close before acquiring more.");
            }
            Image next = queued.pollFirst();
            if (next != null) {
                acquired++;
                held.add(next);
            }
            return next;
        }
    }

    @Implementation
    protected Image acquireLatestImage() {
        synchronized (this) {
            Image newest = null;
            for (Image i; (i = queued.pollFirst()) != null; ) {
                if (newest != null) {
                    newest.close();
                }
                newest = i;
                acquired++;
            }
            if (newest != null) {
                held.add(newest);
            }
            return newest;
        }
    }

    /** Queues an image and tells the app's listener on its handler; false when no listener is set. */
    public boolean deliver(final Image image) {
        final ImageReader.OnImageAvailableListener l;
        Handler h;
        synchronized (this) {
            l = listener;
            h = handler;
            if (l == null || h == null) {
                return false;
            }
            queued.addLast(image);
        }
        return h.post(new Runnable() {
            @Override
            public void run() {
                l.onImageAvailable(reader);
            }
        });
    }

    public ImageReader reader() {
        return reader;
    }

    public synchronized int acquired() {
        return acquired;
    }

    /** Images acquired and not closed yet. */
    public synchronized int open() {
        int open = 0;
        for (Image i : held) {
            open += i instanceof YuvImage && ((YuvImage) i).closed() ? 0 : 1;
        }
        return open;
    }

    public static ShadowYuvImageReader latest() {
        return latest;
    }

    @Resetter
    public static void reset() {
        latest = null;
    }
}
