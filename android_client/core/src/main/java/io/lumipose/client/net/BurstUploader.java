package io.lumipose.client.net;

import java.util.ArrayList;
import java.util.Collections;
import java.util.List;
import java.util.concurrent.Executor;

/**
 * Sends bursts (a pose frame and the ID frames taken after it) as units: one burst in flight, its
 * frames one after the other in order on the executor's thread (so HttpURLConnection reuses one
 * kept-alive connection), and at most one complete burst waiting; a newer burst replaces the
 * waiting one whole (a stale position is worth nothing). Thread-safe; listener calls come on the
 * executor's thread.
 */
public final class BurstUploader {
    /** Told about every frame that was sent. */
    public interface Listener {
        void onResult(FrameUpload frame, LocateResult result);

        /**
         * No answer for this frame (or the server refused the request): the rest of its burst is
         * not sent, since it would most likely fail the same way.
         */
        void onFailure(FrameUpload frame, Exception error);
    }

    private final FrameUploader uploader;
    private final Executor executor;
    private final Listener listener;
    private final Object lock = new Object();
    private List<FrameUpload> waiting;
    private boolean inFlight;
    private boolean closed;
    private long sentBursts;
    private long replacedBursts;

    public BurstUploader(FrameUploader uploader, Executor executor, Listener listener) {
        this.uploader = uploader;
        this.executor = executor;
        this.listener = listener;
    }

    /**
     * Queues a burst (its frames in the order to send them), replacing a burst still waiting. Returns false once closed
     * (or when the executor refuses work), true when queued.
     */
    public boolean submit(List<FrameUpload> burst) {
        if (burst.isEmpty()) {
            throw new IllegalArgumentException("a burst holds at least one frame");
        }
        List<FrameUpload> frames = Collections.unmodifiableList(new ArrayList<FrameUpload>(burst));
        synchronized (lock) {
            if (closed) {
                return false;
            }
            if (waiting != null) {
                replacedBursts++;
            }
            waiting = frames;
            if (inFlight) {
                return true;
            }
            inFlight = true;
        }
        try {
            executor.execute(new Runnable() {
                @Override
                public void run() {
                    drain();
                }
            });
        } catch (RuntimeException e) { // RejectedExecutionException: the executor was shut down
            synchronized (lock) {
                inFlight = false;
                waiting = null;
                closed = true;
            }
            return false;
        }
        return true;
    }

    /** True when a burst submitted now would wait without replacing another: worth copying one. */
    public boolean hasRoom() {
        synchronized (lock) {
            return !closed && waiting == null;
        }
    }

    /** True while a burst is being sent or waits. */
    public boolean busy() {
        synchronized (lock) {
            return inFlight;
        }
    }

    public long sentBursts() {
        synchronized (lock) {
            return sentBursts;
        }
    }

    /** Bursts replaced by a newer one, or dropped at close, before any of their frames was sent. */
    public long replacedBursts() {
        synchronized (lock) {
            return replacedBursts;
        }
    }

    /**
     * Drops the waiting burst and refuses new ones; the frame being sent completes (its listener
     * call included), nothing is sent after it.
     */
    public void close() {
        synchronized (lock) {
            closed = true;
            if (waiting != null) {
                replacedBursts++;
            }
            waiting = null;
        }
    }

    private void drain() {
        while (true) {
            List<FrameUpload> burst;
            synchronized (lock) {
                if (waiting == null || closed) {
                    inFlight = false;
                    return;
                }
                burst = waiting;
                waiting = null;
                sentBursts++;
            }
            if (!send(burst)) {
                synchronized (lock) {
                    inFlight = false;
                }
                return;
            }
        }
    }

    /**
     * Sends a burst's frames in order; false when interrupted. After a failure the burst's other ID
     * frames are skipped (the link is slow or refused), but its pose frame still goes: without its
     * IDs it may still be named by the device's track, and its position is what the user waits for.
     */
    private boolean send(List<FrameUpload> burst) {
        boolean failed = false;
        for (FrameUpload frame : burst) {
            synchronized (lock) {
                if (closed) {
                    return true;
                }
            }
            if (failed && frame.isId()) {
                continue;
            }
            LocateResult result;
            try {
                result = uploader.upload(frame.luma, frame.meta);
            } catch (InterruptedException e) {
                Thread.currentThread().interrupt();
                return false;
            } catch (Exception e) {
                listener.onFailure(frame, e);
                failed = true;
                continue;
            }
            listener.onResult(frame, result);
        }
        return true;
    }
}
