package io.lumipose.client.net;

import java.util.concurrent.Executor;

import io.lumipose.client.frame.FrameMeta;

/**
 * Keeps at most one frame in flight; while it is, only the newest submitted frame waits, and any
 * older waiting frame is dropped (a stale position is worth nothing). Listener calls come on the
 * executor's thread.
 */
public final class LatestFrameUploader {
    /** Told about every frame that was sent. */
    public interface Listener {
        void onResult(FrameMeta meta, LocateResult result);

        void onFailure(FrameMeta meta, Exception error);
    }

    private final FrameUploader uploader;
    private final Executor executor;
    private final Listener listener;
    private final Object lock = new Object();
    private byte[] pendingLuma;
    private FrameMeta pendingMeta;
    private boolean inFlight;
    private boolean closed;
    private long dropped;
    private long sent;

    public LatestFrameUploader(FrameUploader uploader, Executor executor, Listener listener) {
        this.uploader = uploader;
        this.executor = executor;
        this.listener = listener;
    }

    /** Queues a frame, replacing any frame still waiting. Returns false once closed. */
    public boolean submit(byte[] luma, FrameMeta meta) {
        boolean start;
        synchronized (lock) {
            if (closed) {
                return false;
            }
            if (pendingLuma != null) {
                dropped++;
            }
            pendingLuma = luma;
            pendingMeta = meta;
            start = !inFlight;
            inFlight = true;
        }
        if (start) {
            executor.execute(new Runnable() {
                @Override
                public void run() {
                    drain();
                }
            });
        }
        return true;
    }

    /** True while a frame is being sent or waits: the camera can skip copying a new one. */
    public boolean busy() {
        synchronized (lock) {
            return inFlight;
        }
    }

    public long droppedCount() {
        synchronized (lock) {
            return dropped;
        }
    }

    public long sentCount() {
        synchronized (lock) {
            return sent;
        }
    }

    /** Drops a waiting frame and refuses new ones; a frame in flight still completes. */
    public void close() {
        synchronized (lock) {
            closed = true;
            if (pendingLuma != null) {
                dropped++;
            }
            pendingLuma = null;
            pendingMeta = null;
        }
    }

    private void drain() {
        while (true) {
            byte[] luma;
            FrameMeta meta;
            synchronized (lock) {
                if (pendingLuma == null) {
                    inFlight = false;
                    return;
                }
                luma = pendingLuma;
                meta = pendingMeta;
                pendingLuma = null;
                pendingMeta = null;
                sent++;
            }
            try {
                LocateResult r = uploader.upload(luma, meta);
                listener.onResult(meta, r);
            } catch (InterruptedException e) {
                Thread.currentThread().interrupt();
                synchronized (lock) {
                    inFlight = false;
                }
                return;
            } catch (Exception e) {
                listener.onFailure(meta, e);
            }
        }
    }
}
