package io.lumipose.client.replay;

import java.io.IOException;
import java.nio.ByteBuffer;
import java.util.ArrayList;
import java.util.List;
import java.util.Random;

import io.lumipose.client.camera.FrameResult;
import io.lumipose.client.flow.FrameSink;

/**
 * Plays a recording as a phone's camera would: for each frame its TotalCaptureResult (a
 * {@link FrameResult} read from the {@link SimulatedPhone}'s JSON) and its Y plane, on one thread,
 * in the order Camera2 gives no promise about: sometimes the image first, sometimes the result
 * only after the next frame's image. The Y plane comes in one reused direct buffer whose rows are
 * longer than the image is wide and whose last row has no padding, as real phones deliver it.
 * The phone's gravity reading for a frame reaches {@link Gravity} before the frame.
 */
public final class ReplayCamera {
    /** Where the phone's TYPE_GRAVITY readings go (the app's sensor listener). */
    public interface Gravity {
        void onGravity(long timestampNs, float[] valuesDevice);
    }

    /** What the camera writes over a buffer it takes back: a sink must copy what it keeps. */
    static final byte REUSED = (byte) 0x5A;
    private final Recording recording;
    private final SimulatedPhone phone;
    private final long orderSeed;

    public ReplayCamera(Recording recording) {
        this(recording, 12);
    }

    /** @param orderSeed picks which frames arrive image first and whose result comes late */
    public ReplayCamera(Recording recording, long orderSeed) {
        this.recording = recording;
        this.phone = new SimulatedPhone(recording.frames());
        this.orderSeed = orderSeed;
    }

    public Recording recording() {
        return recording;
    }

    public SimulatedPhone phone() {
        return phone;
    }

    /** Camera2 aligns rows to 64 bytes; a row always ends in padding here so a sink must honour the stride. */
    public static int rowStride(int width) {
        return (width / 64 + 1) * 64;
    }

    /** Hands every frame to {@code sink} on this thread, each frame's gravity to {@code gravity} first. */
    public void play(FrameSink sink, Gravity gravity) throws IOException {
        play(recording.frames(), sink, gravity);
    }

    /** As {@link #play(FrameSink, Gravity)}, for some of the recording's frames (in the order given). */
    public void play(List<RecordedFrame> frames, FrameSink sink, Gravity gravity) throws IOException {
        ByteBuffer plane = null;
        for (Event e : events(frames)) {
            RecordedFrame f = e.frame;
            if (e.gravityFirst) {
                float[] g = phone.gravity(f);
                if (g != null) {
                    gravity.onGravity(f.timestampNs, g);
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
                sink.onResult(FrameResult.fromJson(phone.result(f)));
            }
        }
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

    /** One call to the sink: a frame's image, or its result. */
    static final class Event {
        final RecordedFrame frame;
        final boolean image;
        /** The frame's gravity reading is delivered right before this, its first event. */
        boolean gravityFirst;

        Event(RecordedFrame frame, boolean image) {
            this.frame = frame;
            this.image = image;
        }

        @Override
        public String toString() {
            return (image ? "image " : "result ") + frame.name;
        }
    }

    /**
     * The calls in delivery order: a third of the frames image first, and a quarter of the results
     * late, after the next frame's image.
     */
    List<Event> events(List<RecordedFrame> frames) {
        Random random = new Random(orderSeed);
        List<Event> out = new ArrayList<Event>();
        Event late = null;
        for (RecordedFrame f : frames) {
            Event image = new Event(f, true);
            Event result = new Event(f, false);
            boolean imageFirst = random.nextInt(3) == 0;
            boolean resultLate = random.nextInt(4) == 0;
            List<Event> frameEvents = new ArrayList<Event>();
            if (imageFirst || resultLate) {
                frameEvents.add(image);
                if (!resultLate) {
                    frameEvents.add(result);
                }
            } else {
                frameEvents.add(result);
                frameEvents.add(image);
            }
            frameEvents.get(0).gravityFirst = true;
            if (late != null) {
                frameEvents.add(frameEvents.indexOf(image) + 1, late);  // the previous frame's result
                late = null;
            }
            out.addAll(frameEvents);
            if (resultLate) {
                late = result;
            }
        }
        if (late != null) {
            out.add(late);
        }
        return out;
    }
}
