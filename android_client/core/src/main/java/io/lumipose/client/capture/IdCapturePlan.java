package io.lumipose.client.capture;

import java.util.ArrayList;
import java.util.List;

import io.lumipose.client.protocol.CaptureProtocol;

/**
 * Settings of the short-exposure beacon-ID (VLC) frames taken beside pose frames, after the
 * project's capture protocol ({@link CaptureProtocol}, written from server/vlc/capture.py): an
 * exposure the server still reads (at most {@link CaptureProtocol#ID_MAX_EXPOSURE_NS}, one code chip),
 * ISO raised so the panel stays well below clipping, and a burst of {@link CaptureProtocol#ID_BURST_FRAMES}
 * frames whose interval advances the beacon's repeating message by {@link CaptureProtocol#ID_BURST_STEP}
 * of its period from one ID frame to the next, so together they see the whole code (docs/vlc.md).
 */
public final class IdCapturePlan {
    /** ID frames after each pose frame: the protocol's burst. */
    public static final int BURST_FRAMES = CaptureProtocol.ID_BURST_FRAMES;
    /** ID-frame brightness as a fraction of the pose frame's (exposure x ISO): the protocol's. */
    public static final double DEFAULT_BRIGHTNESS_FRACTION = CaptureProtocol.ID_BRIGHTNESS_FRACTION;

    private IdCapturePlan() {
    }

    public static long messagePeriodNs() {
        return CaptureProtocol.messagePeriodNs();
    }

    /**
     * The frame interval nearest {@code nominalNs} that advances the message phase by
     * {@code step} periods (in (0, 1)), never shorter than {@code minimumNs}.
     */
    public static long steppedIntervalNs(long nominalNs, long minimumNs, double step) {
        if (nominalNs <= 0) {
            throw new IllegalArgumentException("nominal frame interval must be > 0 ns, got " + nominalNs);
        }
        if (!(step > 0 && step < 1)) {
            throw new IllegalArgumentException("step must be a fraction of a period in (0, 1), got " + step);
        }
        double period = messagePeriodNs();
        long whole = Math.max(0, Math.round(nominalNs / period - step));
        while ((whole + step) * period < minimumNs) {
            whole++;
        }
        return Math.round((whole + step) * period);
    }

    /**
     * @param ranges             what the camera advertises
     * @param idExposureNs       wanted ID exposure (see {@link CaptureSettingsChooser#DEFAULT_ID_EXPOSURE_NS})
     * @param pose               the pose frames' settings (their exposure x ISO is the reference brightness)
     * @param brightnessFraction ID-frame brightness relative to the pose frame's, in (0, 1]
     * @throws UnsupportedCameraException when the exposure the camera can take is longer than the
     *                                    server reads: its ID frames would all be refused
     */
    public static CaptureSettings choose(CameraRanges ranges, long idExposureNs, CaptureSettings pose,
                                         double brightnessFraction) throws UnsupportedCameraException {
        if (!(brightnessFraction > 0 && brightnessFraction <= 1)) {
            throw new IllegalArgumentException("brightnessFraction must be in (0, 1], got " + brightnessFraction);
        }
        CaptureSettings base = CaptureSettingsChooser.choose(ranges, idExposureNs);
        if (base.exposureNs > CaptureProtocol.ID_MAX_EXPOSURE_NS) {
            throw new UnsupportedCameraException("ID exposure " + base.exposureNs + " ns is longer than the "
                    + CaptureProtocol.ID_MAX_EXPOSURE_NS + " ns the server reads (one code chip): the code would be "
                    + "averaged away, so beacon IDs cannot be read with this camera and exposure.");
        }
        List<String> notes = new ArrayList<String>(base.notes);
        Integer iso = base.sensitivityIso;
        if (iso != null && pose.sensitivityIso != null) {
            double wanted = pose.sensitivityIso * ((double) pose.exposureNs / base.exposureNs) * brightnessFraction;
            iso = (int) Math.round(Math.max(ranges.sensitivityMinIso, Math.min(ranges.sensitivityMaxIso, wanted)));
            if (iso < wanted * 0.999) {
                notes.add("ID ISO " + Math.round(wanted) + " clamped to " + iso + ": the stripes are dimmer");
            }
        }
        long frameNs = steppedIntervalNs(Math.max(base.frameDurationNs, ranges.streamMinFrameDurationNs),
                Math.max(base.exposureNs, ranges.streamMinFrameDurationNs), CaptureProtocol.ID_BURST_STEP);
        if (ranges.maxFrameDurationNs != null && frameNs > ranges.maxFrameDurationNs) {
            notes.add("stepped ID frame interval " + frameNs + " ns exceeds SENSOR_INFO_MAX_FRAME_DURATION");
            frameNs = ranges.maxFrameDurationNs;
        }
        return new CaptureSettings(base.exposureNs, iso, frameNs, notes);
    }
}
