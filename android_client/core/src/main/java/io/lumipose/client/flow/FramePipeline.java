package io.lumipose.client.flow;

import java.nio.ByteBuffer;
import java.util.ArrayList;
import java.util.Iterator;
import java.util.LinkedHashMap;
import java.util.LinkedHashSet;
import java.util.List;
import java.util.Map;
import java.util.Set;
import java.util.TreeMap;
import java.util.concurrent.Executor;

import io.lumipose.client.camera.CameraFacts;
import io.lumipose.client.capture.FrameDescriber;
import io.lumipose.client.camera.FrameResult;
import io.lumipose.client.capture.CapturePlan;
import io.lumipose.client.capture.RequestSpec;
import io.lumipose.client.frame.BeaconWindow;
import io.lumipose.client.frame.FrameMeta;
import io.lumipose.client.frame.Window;
import io.lumipose.client.net.BurstUploader;
import io.lumipose.client.net.FrameUpload;
import io.lumipose.client.net.FrameUploader;
import io.lumipose.client.net.LocateResult;
import io.lumipose.client.sensor.GravityHistory;
import io.lumipose.client.sensor.GyroHistory;

/**
 * What happens to a frame after the camera hands it over (docs/android.md): its capture result
 * and image are matched by SENSOR_TIMESTAMP, the {@link FrameDescriber} says what the frame is
 * (pose or ID, from the exposure the result reports) with the attitude at its timestamp, and a
 * burst (a pose frame and the plan's ID frames after it) goes to the {@link BurstUploader} as one
 * unit, its ID frames first (the server keeps them for the device's next pose frame, so the pose
 * frame gets its own burst's beacon readings). Each frame is cut to the window around the panel:
 * a pose frame to its {@link BeaconWindow} (the whole plane only when none is found), an ID frame
 * to its burst's pose window with a margin for the panel's motion until then (the decoder reads
 * the stripes on the panel's rows). Each window goes with its whole plane's grey levels
 * ({@code crop.levels_dn}), so the server reads it as the whole frame.
 *
 * <p>Whether a burst goes is decided at its pose frame's first half (result or image): when the
 * uploader already holds a burst waiting, or one is in flight and the burst being gathered will
 * wait, the whole burst is dropped before any of it is searched or copied. Camera calls come on the
 * camera's one thread, results on the uploader's; the matching and burst state is guarded by this
 * object's lock only so that {@link #close()} may come from any thread.
 */
public final class FramePipeline implements FrameSink {
    /** What the pipeline tells the screen. */
    public interface Listener {
        /** A pose frame's answer: the position to show and track. On the uploader's thread. */
        void onPoseResult(FrameMeta meta, LocateResult result);

        /** An ID frame's answer (the beacon reading): never a position to show or track. Uploader's thread. */
        void onIdResult(FrameMeta meta, LocateResult result);

        /** A frame not sent, and why ({@link #dropCounts()} keeps the counts). On the camera's thread. */
        void onDropped(String reason);

        /** A frame that got no answer. On the uploader's thread. */
        void onFailure(FrameMeta meta, Exception error);
    }

    public static final String DROP_UPLOADER_BUSY = "uploader busy with the previous bursts";
    public static final String DROP_NO_PANEL_FOR_ID = "no panel in the burst's pose frame";
    public static final String DROP_NO_POSE = "ID frame without its pose frame";
    public static final String DROP_NO_IMAGE = "capture result without its image";
    public static final String DROP_NO_RESULT = "image without its capture result";
    public static final String DROP_OUT_OF_ORDER = "image came before its result, out of the burst's order";
    public static final String DROP_CLOSED = "pipeline closed";
    /** Said once when SENSOR_TIMESTAMP is not on the sensors' clock. */
    public static final String NO_RATE_UNKNOWN_TIMESTAMPS = "camera timestamps not REALTIME: frames go without "
            + "the gyroscope's rate (the rolling shutter's skew stays uncorrected)";

    /**
     * An ID window reaches this share of the pose window's height beyond it, above and below: the
     * panel moves until the burst's last ID frame, and every row over it carries chips of the code.
     */
    public static final double ID_WINDOW_ROW_GROWTH = 0.25;
    /** ... and this share of its width left and right: a panel cut at a side keeps all its rows. */
    public static final double ID_WINDOW_COLUMN_GROWTH = 0.1;
    /** Distinct warnings kept: a few kinds repeat on every frame, numbers in them could make many. */
    static final int MAX_WARNINGS = 20;

    private final FrameDescriber describer;
    private final PlaneWork work;
    private final GravityHistory attitude;
    private final GyroHistory rates;
    private final boolean timestampsRealtime;
    private final int idFramesPerBurst;
    private final BurstUploader uploader;
    private final Listener listener;
    /** Results or images waiting for their other half: a burst's worth and a little more. */
    private final int maxUnmatched;

    // camera thread only
    private final LinkedHashMap<Long, FrameResult> results = new LinkedHashMap<Long, FrameResult>();
    private final LinkedHashMap<Long, EarlyImage> images = new LinkedHashMap<Long, EarlyImage>();
    private Burst burst;
    /** Images seen: an image's number in arrival order, for guessing the kind of one that comes first. */
    private long imageCount;
    /** The last image whose result showed a pose frame, or -1. */
    private long lastPoseByResult = -1;
    /** The last image guessed a pose frame whose result has not come yet, or -1. */
    private long guessedPose = -1;
    /** The last pose frame's ID window, for the ID frames after it. */
    private Window lastIdWindow;
    private boolean closed;
    private long burstsSubmitted;

    // any thread
    private final Map<String, Long> drops = new TreeMap<String, Long>();
    /** The describer's warnings, each once, in the order first seen (a few kinds: bounded). */
    private final Set<String> warnings = new LinkedHashSet<String>();

    /**
     * @param rates              the gyroscope's readings: each frame gets the mean rate over its readout
     * @param timestampsRealtime whether SENSOR_TIMESTAMP shares the sensor events' clock (then the
     *                           attitude is taken at the frame's timestamp, else the latest, and no rate)
     * @param idFramesPerBurst   the plan's ID frames after each pose frame (0: every burst is a pose frame)
     */
    public FramePipeline(FrameDescriber describer, GravityHistory attitude, GyroHistory rates,
                         boolean timestampsRealtime, int idFramesPerBurst, FrameUploader uploader,
                         Executor uploadExecutor, Listener listener) {
        this(describer, attitude, rates, timestampsRealtime, idFramesPerBurst, uploader, uploadExecutor, listener,
                PlaneWork.PIXELS);
    }

    /** The same with the pixel work given (a test counts it). */
    FramePipeline(FrameDescriber describer, GravityHistory attitude, GyroHistory rates, boolean timestampsRealtime,
                  int idFramesPerBurst, FrameUploader uploader, Executor uploadExecutor, Listener listener,
                  PlaneWork work) {
        if (idFramesPerBurst < 0) {
            throw new IllegalArgumentException("idFramesPerBurst must be >= 0, got " + idFramesPerBurst);
        }
        this.describer = describer;
        this.work = work;
        this.attitude = attitude;
        this.rates = rates;
        this.timestampsRealtime = timestampsRealtime;
        if (!timestampsRealtime) {
            warnings.add(NO_RATE_UNKNOWN_TIMESTAMPS);
        }
        this.idFramesPerBurst = idFramesPerBurst;
        this.listener = listener;
        this.maxUnmatched = idFramesPerBurst + 3;
        this.uploader = new BurstUploader(uploader, uploadExecutor, new BurstUploader.Listener() {
            @Override
            public void onResult(FrameUpload frame, LocateResult result) {
                if (frame.isId()) {
                    FramePipeline.this.listener.onIdResult(frame.meta, result);
                } else {
                    FramePipeline.this.listener.onPoseResult(frame.meta, result);
                }
            }

            @Override
            public void onFailure(FrameUpload frame, Exception error) {
                FramePipeline.this.listener.onFailure(frame.meta, error);
            }
        });
    }

    /** The pipeline for one opened camera and its plan, as the app builds it. */
    public static FramePipeline forCamera(CameraFacts facts, CapturePlan plan, Double mapXBearingDeg,
                                          GravityHistory attitude, GyroHistory rates, FrameUploader uploader,
                                          Executor uploadExecutor, Listener listener) {
        return forCamera(new FrameDescriber(facts, plan, mapXBearingDeg), facts, plan, attitude, rates, uploader,
                uploadExecutor, listener);
    }

    /** The same with the screen's own describer (a calibrated profile, say). */
    public static FramePipeline forCamera(FrameDescriber describer, CameraFacts facts, CapturePlan plan,
                                          GravityHistory attitude, GyroHistory rates, FrameUploader uploader,
                                          Executor uploadExecutor, Listener listener) {
        return new FramePipeline(describer, attitude, rates, facts.timestampsAreRealtime(), plan.idFramesPerBurst,
                uploader, uploadExecutor, listener);
    }

    @Override
    public synchronized void onResult(FrameResult result) {
        if (closed) {
            return;
        }
        EarlyImage image = images.remove(result.timestampNs);
        if (image != null) {
            handle(result, image);
            return;
        }
        results.put(result.timestampNs, result);
        evictOldest(results, DROP_NO_IMAGE);
    }

    @Override
    public synchronized void onImage(long timestampNs, ByteBuffer yPlane, int width, int height, int rowStride,
                                     int pixelStride) {
        if (closed) {
            return;
        }
        long number = imageCount++;
        FrameResult result = results.remove(timestampNs);
        if (result != null) {
            handle(result, new LivePlane(work, number, yPlane, width, height, rowStride, pixelStride));
            return;
        }
        images.put(timestampNs, copyEarly(number, yPlane, width, height, rowStride, pixelStride));
        evictOldest(images, DROP_NO_RESULT);
    }

    /**
     * Drops whatever waits (a burst being gathered, a burst waiting to be sent) and ignores later
     * frames; the frame in flight completes. Any thread.
     */
    public synchronized void close() {
        closed = true;
        if (burst != null && burst.kept) {
            drop(DROP_CLOSED, burst.inOrder().size());
        }
        burst = null;
        drop(DROP_CLOSED, results.size() + images.size());
        results.clear();
        images.clear();
        uploader.close();
    }

    /** Frames not sent so far, by reason. */
    public Map<String, Long> dropCounts() {
        synchronized (drops) {
            return new TreeMap<String, Long>(drops);
        }
    }

    /** What the describer warned about so far (optical stabilisation left on, ...), each once. */
    public List<String> warnings() {
        synchronized (warnings) {
            return new ArrayList<String>(warnings);
        }
    }

    /** True while a burst is being sent or waits. */
    public boolean uploading() {
        return uploader.busy();
    }

    /** Bursts handed to the uploader so far. */
    public synchronized long burstsSubmitted() {
        return burstsSubmitted;
    }

    private void handle(FrameResult result, Pixels pixels) {
        GravityHistory.Attitude a = attitude.forFrame(result.timestampNs, timestampsRealtime);
        float[] rate = rates.forFrame(result.timestampNs, readoutEndNs(result), timestampsRealtime);
        FrameDescriber.Described d = describer.describe(result, a.gravity, a.rotationToEnu, rate);
        noteWarnings(d.warnings);
        // The burst goes by what each frame is (its result), never by its request's tag: without
        // per-frame control the tags run some frames ahead of the exposures.
        boolean pose = RequestSpec.POSE.equals(d.kind);
        notePoseImage(pixels.number(), pose);
        if (d.meta == null) {
            drop(d.dropReason, 1);
            if (pose) {
                submitBurst(); // its ID frames have no pose frame to go with
            } else if (burst != null && burst.remaining > 0 && --burst.remaining == 0) {
                submitBurst(); // one of the burst's ID frames: it goes without it
            }
            return;
        }
        if (pose) {
            handlePose(d.meta, pixels);
        } else {
            handleId(d.meta, pixels);
        }
    }

    /**
     * When the last row's exposure ends: SENSOR_TIMESTAMP is the first row's start, the last row
     * starts a skew later (a missing skew or exposure counts as none).
     */
    static long readoutEndNs(FrameResult result) {
        long skew = result.rollingShutterSkewNs == null ? 0 : result.rollingShutterSkewNs;
        long exposure = result.exposureNs == null ? 0 : result.exposureNs;
        return result.timestampNs + skew + exposure;
    }

    /**
     * Keeps the guess of which early image is a pose frame in step with the results: once an
     * image's result has come it speaks instead of the guess, and a guess it refutes gives the
     * ID window back to the burst being gathered.
     */
    private void notePoseImage(long number, boolean pose) {
        if (pose) {
            lastPoseByResult = Math.max(lastPoseByResult, number);
        }
        if (number == guessedPose) {
            guessedPose = -1;
            if (!pose) {
                lastIdWindow = burst == null ? null : burst.idWindow;
            }
        }
    }

    /**
     * Whether an image that came before its result is an ID frame: the bursts repeat, so it is
     * one unless a whole number of bursts separates it from the last pose frame a result showed
     * (before any, the last image guessed one). The exposures keep this rhythm whatever the tags
     * say (a settings lag moves only the tags); a frame of the settings' transition at the start
     * can mislead a guess, which costs the burst it falls in until a result shows a pose frame.
     */
    private boolean guessId(long number) {
        long lastPose = lastPoseByResult >= 0 ? lastPoseByResult : guessedPose;
        return lastPose >= 0 && (number - lastPose) % (idFramesPerBurst + 1) != 0;
    }

    private void handlePose(FrameMeta meta, Pixels pixels) {
        submitBurst();
        if (pixels.skippedBusy() || !roomForNextBurst()) {
            burst = Burst.dropped(idFramesPerBurst);
            lastIdWindow = null;
            drop(DROP_UPLOADER_BUSY, 1);
            return;
        }
        if (!pixels.panelSearched()) {
            burst = Burst.dropped(idFramesPerBurst);
            drop(DROP_OUT_OF_ORDER, 1);
            return;
        }
        Window panel = pixels.panel();
        Window sent = panel != null ? panel : new Window(0, 0, meta.width, meta.height);
        byte[] luma = pixels.copy(sent);
        if (luma == null) {
            burst = Burst.dropped(idFramesPerBurst);
            drop(DROP_UPLOADER_BUSY, 1);
            return;
        }
        lastIdWindow = idWindow(panel, meta.width, meta.height);
        burst = new Burst(lastIdWindow, idFramesPerBurst);
        burst.pose = new FrameUpload(luma, cut(meta, panel, pixels));
        if (burst.remaining == 0) {
            submitBurst();
        }
    }

    private void handleId(FrameMeta meta, Pixels pixels) {
        if (burst == null || burst.remaining == 0) {
            drop(DROP_NO_POSE, 1);
            return;
        }
        burst.remaining--;
        if (!burst.kept) {
            drop(DROP_UPLOADER_BUSY, 1);
        } else if (burst.idWindow == null) {
            drop(DROP_NO_PANEL_FOR_ID, 1);
        } else {
            byte[] luma = pixels.copy(burst.idWindow);
            if (luma == null) {
                drop(DROP_OUT_OF_ORDER, 1);
            } else {
                burst.ids.add(new FrameUpload(luma, cut(meta, burst.idWindow, pixels)));
            }
        }
        if (burst.remaining == 0) {
            submitBurst();
        }
    }

    /** Hands the burst being gathered to the uploader, complete or not (an ID frame may have been dropped). */
    private void submitBurst() {
        Burst b = burst;
        burst = null;
        if (b == null || !b.kept) {
            return;
        }
        if (uploader.submit(b.inOrder())) {
            burstsSubmitted++;
        } else {
            drop(DROP_CLOSED, b.inOrder().size());
        }
    }

    /**
     * The window of a burst's ID frames: the pose frame's panel window grown for the panel's
     * motion until the burst's last ID frame (~0.15 s), more in rows than in columns, since the
     * decoder reads the code along the rows over the panel (docs/vlc.md, "Cut panels").
     */
    static Window idWindow(Window panel, int width, int height) {
        return panel == null ? null : panel.grown(ID_WINDOW_COLUMN_GROWTH, ID_WINDOW_ROW_GROWTH, width, height);
    }

    /** The frame's JSON for the window w (null: the whole frame), with its whole plane's grey levels. */
    private static FrameMeta cut(FrameMeta meta, Window w, Pixels pixels) {
        return w == null ? meta : meta.window(w.x0, w.y0, w.width(), w.height(), pixels.levels());
    }

    /**
     * Whether a burst whose pose frame comes now would find the uploader's waiting place free when
     * it is complete: not when a burst is in flight and the one being gathered will take that place.
     * (Should the burst in flight end first, this burst is lost though it had room: one burst, not a
     * search and a copy of every burst the uploader cannot take.)
     */
    private boolean roomForNextBurst() {
        boolean gatheredWillWait = burst != null && burst.kept && uploader.busy();
        return !gatheredWillWait && uploader.hasRoom();
    }

    /**
     * An image whose result has not come: its kind is guessed from the burst's order
     * ({@link #guessId}), and only what that kind needs is copied; the result checks it. A guessed
     * pose frame the uploader has no room for is neither searched nor copied (its burst is dropped
     * at its result), and neither are its ID frames.
     */
    private EarlyImage copyEarly(long number, ByteBuffer plane, int width, int height, int rowStride,
                                 int pixelStride) {
        if (guessId(number)) {
            Window w = lastIdWindow;
            return new EarlyImage(work, number, false, null, w,
                    w == null ? null : work.copyWindow(plane, width, height, rowStride, pixelStride, w),
                    w == null ? null : work.levels(plane, width, height, rowStride, pixelStride));
        }
        guessedPose = number;
        if (!roomForNextBurst()) {
            lastIdWindow = null;
            return EarlyImage.skipped(work, number);
        }
        Window panel = work.findPanel(plane, width, height, rowStride, pixelStride);
        lastIdWindow = idWindow(panel, width, height);
        // no panel: the whole plane goes (the server says why), but only when there is room for it
        Window region = panel != null ? panel : uploader.hasRoom() ? new Window(0, 0, width, height) : null;
        return new EarlyImage(work, number, true, panel, region,
                region == null ? null : work.copyWindow(plane, width, height, rowStride, pixelStride, region),
                panel == null ? null : work.levels(plane, width, height, rowStride, pixelStride));
    }

    private <V> void evictOldest(LinkedHashMap<Long, V> waiting, String reason) {
        Iterator<Long> it = waiting.keySet().iterator();
        while (waiting.size() > maxUnmatched) {
            it.next();
            it.remove();
            drop(reason, 1);
        }
    }

    private void noteWarnings(List<String> seen) {
        synchronized (warnings) {
            for (String w : seen) {
                if (warnings.size() < MAX_WARNINGS) {
                    warnings.add(w);
                }
            }
        }
    }

    private void drop(String reason, int frames) {
        if (frames <= 0) {
            return;
        }
        synchronized (drops) {
            Long n = drops.get(reason);
            drops.put(reason, (n == null ? 0 : n) + frames);
        }
        for (int i = 0; i < frames; i++) {
            listener.onDropped(reason);
        }
    }

    /** A pose frame and the ID frames gathered after it. */
    private static final class Burst {
        final boolean kept;
        /** The window its ID frames are cut to; null when the pose frame showed no panel. */
        final Window idWindow;
        FrameUpload pose;
        final List<FrameUpload> ids = new ArrayList<FrameUpload>();
        /** ID frames still to come. */
        int remaining;

        Burst(Window idWindow, int idFrames) {
            this(true, idWindow, idFrames);
        }

        private Burst(boolean kept, Window idWindow, int idFrames) {
            this.kept = kept;
            this.idWindow = idWindow;
            this.remaining = idFrames;
        }

        static Burst dropped(int idFrames) {
            return new Burst(false, null, idFrames);
        }

        /**
         * The order the server needs: it keeps a device's ID frames for its next pose frame, so
         * the ID frames go first and the pose frame combines its own burst's readings.
         */
        List<FrameUpload> inOrder() {
            List<FrameUpload> frames = new ArrayList<FrameUpload>(ids);
            frames.add(pose);
            return frames;
        }
    }

    /** A frame's pixels while it is handled. */
    private interface Pixels {
        /** The image's number in arrival order. */
        long number();

        /** Whether {@link #panel()} was looked for. */
        boolean panelSearched();

        /** Whether nothing was kept because the uploader had no room when the image came. */
        boolean skippedBusy();

        /** The frame's beacon window, or null when no panel stands out. */
        Window panel();

        /** The packed pixels of a window, or null when they were not kept. */
        byte[] copy(Window w);

        /**
         * The whole plane's [background, plateau] by the contract's coarse rule, sent with its window
         * ({@code crop.levels_dn}) so the server reads the window as the whole frame.
         */
        double[] levels();
    }

    /** The camera's plane, during the onImage call. */
    private static final class LivePlane implements Pixels {
        private final PlaneWork work;
        private final long number;
        private final ByteBuffer plane;
        private final int width;
        private final int height;
        private final int rowStride;
        private final int pixelStride;

        LivePlane(PlaneWork work, long number, ByteBuffer plane, int width, int height, int rowStride,
                  int pixelStride) {
            this.work = work;
            this.number = number;
            this.plane = plane;
            this.width = width;
            this.height = height;
            this.rowStride = rowStride;
            this.pixelStride = pixelStride;
        }

        @Override
        public long number() {
            return number;
        }

        @Override
        public boolean panelSearched() {
            return true;
        }

        @Override
        public boolean skippedBusy() {
            return false;
        }

        @Override
        public Window panel() {
            return work.findPanel(plane, width, height, rowStride, pixelStride);
        }

        @Override
        public byte[] copy(Window w) {
            return work.copyWindow(plane, width, height, rowStride, pixelStride, w);
        }

        @Override
        public double[] levels() {
            return work.levels(plane, width, height, rowStride, pixelStride);
        }
    }

    /** What was kept of an image that came before its result. */
    private static final class EarlyImage implements Pixels {
        private final PlaneWork work;
        private final long number;
        private final boolean skippedBusy;
        private final boolean panelSearched;
        private final Window panel;
        private final Window region;
        private final byte[] pixels;
        private final double[] levels;

        EarlyImage(PlaneWork work, long number, boolean panelSearched, Window panel, Window region, byte[] pixels,
                   double[] levels) {
            this(work, number, false, panelSearched, panel, region, pixels, levels);
        }

        private EarlyImage(PlaneWork work, long number, boolean skippedBusy, boolean panelSearched, Window panel,
                           Window region, byte[] pixels, double[] levels) {
            this.work = work;
            this.number = number;
            this.skippedBusy = skippedBusy;
            this.panelSearched = panelSearched;
            this.panel = panel;
            this.region = region;
            this.pixels = pixels;
            this.levels = levels;
        }

        @Override
        public double[] levels() {
            return levels;
        }

        @Override
        public long number() {
            return number;
        }

        /** A guessed pose frame the uploader had no room for: nothing looked at, nothing kept. */
        static EarlyImage skipped(PlaneWork work, long number) {
            return new EarlyImage(work, number, true, false, null, null, null, null);
        }

        @Override
        public boolean panelSearched() {
            return panelSearched;
        }

        @Override
        public boolean skippedBusy() {
            return skippedBusy;
        }

        @Override
        public Window panel() {
            return panel;
        }

        @Override
        public byte[] copy(Window w) {
            if (region == null || !region.contains(w)) {
                return null;
            }
            if (region.equals(w)) {
                return pixels;
            }
            return work.copyWindow(ByteBuffer.wrap(pixels), region.width(), region.height(), region.width(), 1,
                    new Window(w.x0 - region.x0, w.y0 - region.y0, w.x1 - region.x0, w.y1 - region.y0));
        }
    }
}
