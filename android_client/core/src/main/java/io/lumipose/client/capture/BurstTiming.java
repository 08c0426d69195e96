package io.lumipose.client.capture;

import java.util.ArrayList;
import java.util.Collections;
import java.util.List;

import io.lumipose.client.protocol.CaptureProtocol;

/**
 * How long each frame of the repeating burst lasts (SENSOR_FRAME_DURATION), so that the burst
 * repeats at a stated rate instead of the sensor's fastest: every frame is read out and processed
 * whether the uploader takes it or not (battery and heat, issue 26).
 *
 * <p>The pose frame and the ID frames keep their shortest durations, so the ID frames follow the
 * pose frame at once and each other a quarter message apart (docs/vlc.md); the burst's last frame
 * carries the blanking (the sensor idles after its readout). With ID frames the period stays a
 * whole number of messages plus the golden step, so successive bursts still see the message at
 * evenly spread phases. No frame lasts longer than SENSOR_INFO_MAX_FRAME_DURATION: then the burst
 * repeats faster than asked, said in a note.
 */
final class BurstTiming {
    /** The pose frame's duration, ns. */
    final long poseFrameNs;
    /** Each ID frame's but the last, ns; 0 without ID frames. */
    final long idFrameNs;
    /** The burst's last frame's (the pose frame's when there are no ID frames), ns. */
    final long lastFrameNs;
    /** From one pose frame's start to the next, ns. */
    final long periodNs;
    final List<String> notes;

    private BurstTiming(long poseFrameNs, long idFrameNs, long lastFrameNs, long periodNs, List<String> notes) {
        this.poseFrameNs = poseFrameNs;
        this.idFrameNs = idFrameNs;
        this.lastFrameNs = lastFrameNs;
        this.periodNs = periodNs;
        this.notes = Collections.unmodifiableList(new ArrayList<String>(notes));
    }

    /**
     * @param poseMinimumNs      the pose frame's shortest duration (its exposure, the stream's minimum)
     * @param idFrameNs          each ID frame's stepped duration (ignored without ID frames)
     * @param idFrames           ID frames after the pose frame, 0 for none
     * @param maxFrameDurationNs SENSOR_INFO_MAX_FRAME_DURATION, null when not advertised
     * @param burstsPerSecond    the most bursts a second wanted, > 0
     */
    static BurstTiming of(long poseMinimumNs, long idFrameNs, int idFrames, Long maxFrameDurationNs,
                          double burstsPerSecond) {
        if (!(burstsPerSecond > 0) || Double.isInfinite(burstsPerSecond)) {
            throw new IllegalArgumentException("bursts per second must be > 0, got " + burstsPerSecond);
        }
        if (idFrames < 0) {
            throw new IllegalArgumentException("ID frames must be >= 0, got " + idFrames);
        }
        long wantedNs = Math.round(1e9 / burstsPerSecond);
        List<String> notes = new ArrayList<String>();
        if (idFrames == 0) {
            long frameNs = Math.max(poseMinimumNs, wantedNs);
            if (maxFrameDurationNs != null && frameNs > maxFrameDurationNs) {
                frameNs = Math.max(poseMinimumNs, maxFrameDurationNs);
                notes.add(slowestNote(frameNs, wantedNs, maxFrameDurationNs));
            }
            return new BurstTiming(frameNs, 0, frameNs, frameNs, notes);
        }
        long beforeLastNs = poseMinimumNs + (idFrames - 1) * idFrameNs;
        long shortestNs = beforeLastNs + idFrameNs;
        long target = Math.max(shortestNs, wantedNs);
        long periodNs = IdCapturePlan.steppedIntervalNs(target, target, CaptureProtocol.GOLDEN_STEP);
        if (maxFrameDurationNs != null && periodNs - beforeLastNs > maxFrameDurationNs) {
            long limitNs = beforeLastNs + Math.max(idFrameNs, maxFrameDurationNs);
            long stepped = longestSteppedNs(limitNs, CaptureProtocol.GOLDEN_STEP);
            if (stepped >= shortestNs) {
                periodNs = stepped;
                notes.add(slowestNote(periodNs, wantedNs, maxFrameDurationNs));
            } else {
                periodNs = limitNs;
                notes.add("last frame of the burst " + (periodNs - beforeLastNs) + " ns at "
                        + "SENSOR_INFO_MAX_FRAME_DURATION: bursts are not golden-stepped");
            }
        }
        return new BurstTiming(poseMinimumNs, idFrameNs, periodNs - beforeLastNs, periodNs, notes);
    }

    /** The longest interval of a whole number of messages plus {@code step} not above {@code limitNs}; -1 if none. */
    private static long longestSteppedNs(long limitNs, double step) {
        double period = IdCapturePlan.messagePeriodNs();
        long whole = (long) Math.floor(limitNs / period - step);
        while (whole >= 0 && Math.round((whole + step) * period) > limitNs) {
            whole--;
        }
        return whole < 0 ? -1 : Math.round((whole + step) * period);
    }

    private static String slowestNote(long periodNs, long wantedNs, long maxFrameDurationNs) {
        return String.format(java.util.Locale.ROOT, "bursts every %.1f ms, not the %.1f ms asked: no frame may last "
                + "longer than SENSOR_INFO_MAX_FRAME_DURATION (%.1f ms)", periodNs / 1e6, wantedNs / 1e6,
                maxFrameDurationNs / 1e6);
    }
}
