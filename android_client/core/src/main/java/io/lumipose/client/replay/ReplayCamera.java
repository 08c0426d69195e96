package io.lumipose.client.replay;

import java.io.IOException;
import java.nio.ByteBuffer;
import java.util.ArrayList;
import java.util.Collections;
import java.util.Comparator;
import java.util.HashMap;
import java.util.List;
import java.util.Map;
import java.util.Random;

import io.lumipose.client.camera.CameraFacts;
import io.lumipose.client.camera.FrameResult;
import io.lumipose.client.capture.CaptureOptions;
import io.lumipose.client.capture.CapturePlan;
import io.lumipose.client.capture.RequestSpec;
import io.lumipose.client.flow.FrameSink;
import io.lumipose.client.sensor.GravityHistory;
import io.lumipose.client.sensor.GyroHistory;

/**
 * Plays a recording as the phone's camera would, into the same {@link FrameSink} the app's Camera2
 * controller feeds: the app reads the {@link #facts()} of a {@link SimulatedPhone} whose camera is
 * exactly the recording's, plans its capture ({@link CapturePlan}), and the camera then delivers,
 * for every recorded frame the plan asks for, its TotalCaptureResult (as a {@link FrameResult})
 * and its Y plane, on one thread, in an order Camera2 allows: results in capture order, images in
 * capture order, and between the two sometimes the image first, sometimes the result only after
 * the next frame's image. The Y plane comes in one reused direct buffer whose rows are longer
 * than the image is wide and whose last row has no padding, as phones deliver it. The phone's
 * gravity reading at each frame reaches the {@link GravityHistory} before the frame, and its
 * rotation rate (when the recording states one) the {@link GyroHistory}, stamped mid-readout.
 */
public final class ReplayCamera {
    /** Called before each call to the sink: where a test waits for the uploader, or a player keeps time. */
    public interface Pace {
        void beforeDelivery(RecordedFrame frame) throws InterruptedException;
    }

    /** What the camera writes over a buffer it takes back: a sink must copy what it keeps. */
    static final byte REUSED = (byte) 0x5A;
    private final Recording recording;
    private final SimulatedPhone phone;
    private final long orderSeed;

    public ReplayCamera(Recording recording) {
        this(recording, 12);
    }

    /** @param orderSeed draws when each result arrives relative to the images */
    public ReplayCamera(Recording recording, long orderSeed) {
        this(recording, orderSeed, 0);
    }

    /**
     * A phone without per-frame control: each frame carries the settings of the request
     * {@code settingsLagFrames} frames before it (what the recording rendered) and the tag of the
     * request submitted for it, as a device whose SYNC_MAX_LATENCY is not PER_FRAME_CONTROL does.
     */
    public ReplayCamera(Recording recording, long orderSeed, int settingsLagFrames) {
        this.recording = recording;
        this.phone = new SimulatedPhone(recording.frames(), settingsLagFrames);
        this.orderSeed = orderSeed;
    }

    public Recording recording() {
        return recording;
    }

    public SimulatedPhone phone() {
        return phone;
    }

    /** The camera's characteristics as the app reads them. */
    public CameraFacts facts() {
        return phone.facts();
    }

    /** What the user set: the recording's exposures, for a map of {@code beaconsInMap} beacons. */
    public CaptureOptions captureOptions(int beaconsInMap, double ceilingDistanceM) {
        return phone.captureOptions(beaconsInMap, ceilingDistanceM);
    }

    /** Camera2 aligns rows to 64 bytes; a row always ends in padding here so a sink must honour the stride. */
    public static int rowStride(int width) {
        return (width / 64 + 1) * 64;
    }

    /**
     * Hands every recorded frame the plan asks for to {@code sink} on this thread (an ID frame is
     * left out when the plan takes none), each frame's gravity to {@code gravity} and rotation rate
     * to {@code rates} first.
     *
     * @throws IllegalStateException when the plan streams another size than the recording's
     */
    public void play(CapturePlan plan, FrameSink sink, GravityHistory gravity, GyroHistory rates, Pace pace)
            throws IOException, InterruptedException {
        List<RecordedFrame> taken = new ArrayList<RecordedFrame>();
        for (RecordedFrame f : recording.frames()) {
            if (plan.spec(f.kind) == null) {
                continue;
            }
            if (f.width != plan.output.width || f.height != plan.output.height) {
                throw new IllegalStateException("the plan streams " + plan.output + ", " + f.name + " is " + f.width
                        + "x" + f.height);
            }
            taken.add(f);
        }
        Map<RecordedFrame, RequestSpec> tags = tags(plan, taken);
        ByteBuffer plane = null;
        for (Event e : events(taken)) {
            RecordedFrame f = e.frame;
            pace.beforeDelivery(f);
            if (e.first) {
                float[] g = phone.gravity(f);
                if (g != null) {
                    gravity.addGravity(f.timestampNs, g);
                }
                float[] w = phone.rotationRate(f);
                if (w != null) {
                    rates.add(midReadoutNs(f), w);
                }
            }
            if (e.image) {
                int stride = rowStride(f.width);
                int size = stride * (f.height - 1) + f.width;
                if (plane == null || plane.capacity() < size) {
                    plane = ByteBuffer.allocateDirect(size);
                }
                fill(plane, f, stride, size);
                sink.onImage(f.timestampNs, plane, f.width, f.height, stride, 1);
                scribble(plane);
            } else {
                sink.onResult(FrameResult.fromJson(phone.result(f, plan.spec(f.kind), tags.get(f))));
            }
        }
    }

    /**
     * One reading in the middle of the frame's readout: inside its window, and outside the next
     * frame's (whose readout starts a frame later), so each frame's mean is its own rate.
     */
    private static long midReadoutNs(RecordedFrame f) {
        double skewS = f.rollingShutterSkewS == null ? 0 : f.rollingShutterSkewS;
        return f.timestampNs + Math.round((skewS + f.exposureS) * 1e9 / 2);
    }

    /**
     * The request each frame was submitted for. The camera repeats the plan's burst; a frame shows
     * the settings of the request {@code settingsLagFrames} before its own, so its tag is the
     * request that many places after the one its pixels (its recorded kind) show.
     */
    private Map<RecordedFrame, RequestSpec> tags(CapturePlan plan, List<RecordedFrame> taken) {
        List<RequestSpec> burst = plan.burst();
        Map<RecordedFrame, RequestSpec> tags = new HashMap<RecordedFrame, RequestSpec>();
        int placeInBurst = 0;
        for (RecordedFrame f : taken) {
            placeInBurst = f.isIdFrame() ? placeInBurst + 1 : 0;
            tags.put(f, burst.get((placeInBurst + phone.settingsLagFrames) % burst.size()));
        }
        return tags;
    }

    private static void fill(ByteBuffer plane, RecordedFrame f, int stride, int size) throws IOException {
        byte[] luma = f.luma();
        plane.clear();
        for (int row = 0; row < f.height; row++) {
            plane.position(row * stride);
            plane.put(luma, row * f.width, f.width);
        }
        plane.position(0);
        plane.limit(size);
    }

    private static void scribble(ByteBuffer plane) {
        plane.clear();
        while (plane.hasRemaining()) {
            plane.put(REUSED);
        }
        plane.clear();
    }

    /** One call to the sink: a frame's image, or its result, at its delivery time. */
    static final class Event {
        final RecordedFrame frame;
        final boolean image;
        /** In frame intervals from the first frame's start. */
        final double at;
        /** The frame's first call: its capture starts (and its gravity reading comes) here. */
        boolean first;

        Event(RecordedFrame frame, boolean image, double at) {
            this.frame = frame;
            this.image = image;
            this.at = at;
        }

        @Override
        public String toString() {
            return (image ? "image " : "result ") + frame.name;
        }
    }

    /**
     * The calls in delivery order. Camera2 delivers results in capture order and images in capture
     * order, but promises nothing between the two: here an image comes half a frame after its
     * capture starts, a result anywhere up to 1.8 frames after, never before the previous result.
     * So about a third of the frames come result first, and a sixth of the results come only after
     * the next frame's image.
     */
    List<Event> events(List<RecordedFrame> frames) {
        Random random = new Random(orderSeed);
        List<Event> out = new ArrayList<Event>();
        double lastResult = Double.NEGATIVE_INFINITY;
        for (int i = 0; i < frames.size(); i++) {
            Event image = new Event(frames.get(i), true, i + 0.5);
            lastResult = Math.max(lastResult + 1e-3, i + 1.8 * random.nextDouble());
            Event result = new Event(frames.get(i), false, lastResult);
            (result.at < image.at ? result : image).first = true;
            out.add(image);
            out.add(result);
        }
        Collections.sort(out, new Comparator<Event>() {
            @Override
            public int compare(Event a, Event b) {
                return Double.compare(a.at, b.at);
            }
        });
        return out;
    }
}
