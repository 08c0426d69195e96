package io.lumipose.client.capture;

import java.util.ArrayList;
import java.util.Collections;
import java.util.List;

import io.lumipose.client.camera.ArrayRect;
import io.lumipose.client.camera.CameraFacts;
import io.lumipose.client.camera.OutputSizeChooser;
import io.lumipose.client.camera.PixelSize;
import io.lumipose.client.protocol.CaptureProtocol;

/**
 * What to ask one camera for: the output size, the pose request and, when the map has beacons to
 * tell apart and the camera can show their code, the ID request repeated after each pose frame.
 * A pure function of the camera's facts and the options, so every phone's choice is testable.
 *
 * <p>Timing (docs/vlc.md): the ID frames of a burst start {@code 1/n} of a message apart, and the
 * whole cycle (pose frame plus n ID frames) is a whole number of messages plus the golden step
 * 0.382, so successive bursts see the message at evenly spread phases. The burst repeats at most
 * {@link CaptureOptions#burstsPerSecond} (or {@link CaptureOptions#idBurstsPerSecond} with ID
 * frames) times a second: its last frame takes up the slack ({@link BurstTiming}), the pose and
 * ID frames keep their shortest durations.
 */
public final class CapturePlan {
    /** The output stream's size (YUV_420_888). */
    public final PixelSize output;
    public final RequestSpec pose;
    /** Null when no ID frames are taken. Every ID frame's request but the burst's last, which lasts longer. */
    public final RequestSpec id;
    /** ID frames after each pose frame; 0 without ID frames. */
    public final int idFramesPerBurst;
    /** From one pose frame's start to the next, ns. */
    public final long burstIntervalNs;
    /** The most bursts a second asked for this burst; {@link #burstIntervalNs} is what the camera allows. */
    public final double burstsPerSecond;
    /** What the user should know about this camera's capture, shown on screen. */
    public final List<String> notes;
    /** The burst's last ID request: {@link #id} with the blanking that holds the burst to its rate; null without. */
    private final RequestSpec lastId;
    /** The notes but the timing's, for a plan retimed or changed. */
    private final List<String> settingsNotes;
    /** The pose frame's own minimum duration, before any blanking. */
    private final long poseMinimumFrameNs;
    /** SENSOR_INFO_MAX_FRAME_DURATION, null when not advertised. */
    private final Long maxFrameDurationNs;
    /** The rates asked for pose frames alone and for bursts with ID frames (kept for a plan without them). */
    private final double poseAlonePerSecond;
    private final double withIdFramesPerSecond;

    /**
     * {@code pose} and {@code id} come at their own shortest frame durations: the timing sets the
     * pose frame's and makes the burst's last ID request.
     */
    private CapturePlan(PixelSize output, RequestSpec pose, RequestSpec id, int idFramesPerBurst,
                        List<String> settingsNotes, Long maxFrameDurationNs, double poseAlonePerSecond,
                        double withIdFramesPerSecond) {
        double burstsPerSecond = id == null ? poseAlonePerSecond : withIdFramesPerSecond;
        BurstTiming timing = BurstTiming.of(pose.frameDurationNs, id == null ? 0 : id.frameDurationNs,
                idFramesPerBurst, maxFrameDurationNs, burstsPerSecond);
        this.output = output;
        this.pose = pose.withExposure(RequestSpec.POSE, pose.exposureNs, pose.sensitivityIso, timing.poseFrameNs);
        this.id = id;
        this.lastId = id == null ? null
                : id.withExposure(RequestSpec.ID, id.exposureNs, id.sensitivityIso, timing.lastFrameNs);
        this.idFramesPerBurst = idFramesPerBurst;
        this.burstIntervalNs = timing.periodNs;
        this.burstsPerSecond = burstsPerSecond;
        this.settingsNotes = Collections.unmodifiableList(new ArrayList<String>(settingsNotes));
        List<String> all = new ArrayList<String>(settingsNotes);
        all.addAll(timing.notes);
        this.notes = Collections.unmodifiableList(all);
        this.poseMinimumFrameNs = pose.frameDurationNs;
        this.maxFrameDurationNs = maxFrameDurationNs;
        this.poseAlonePerSecond = poseAlonePerSecond;
        this.withIdFramesPerSecond = withIdFramesPerSecond;
    }

    /**
     * @throws UnsupportedCameraException when the camera cannot take manual frames (no
     *         MANUAL_SENSOR, no exposure range) or offers no usable YUV output
     */
    public static CapturePlan plan(CameraFacts facts, CaptureOptions options) throws UnsupportedCameraException {
        List<String> notes = new ArrayList<String>();
        boolean correctionOff = facts.distortionCorrectionModes.contains("off");
        if (!facts.distortionCorrectionModes.isEmpty() && !correctionOff) {
            notes.add("distortion correction cannot be switched off: no distortion sent");
        }
        // With correction off the crop region is in the pre-correction array: ask for all of it.
        ArrayRect cropArray = correctionOff ? facts.preCorrectionOrActive() : facts.activeArray;
        ArrayRect crop = ArrayRect.ofSize(cropArray.width, cropArray.height);

        PixelSize output;
        try {
            output = OutputSizeChooser.choose(facts.yuvSizes(), crop, options.maxPixels);
        } catch (IllegalArgumentException e) {
            throw new UnsupportedCameraException(e.getMessage());
        }
        CameraRanges ranges = ranges(facts, output);
        CaptureSettings poseSettings = CaptureSettingsChooser.choose(ranges, options.poseExposureNs);
        notes.addAll(poseSettings.notes);

        Float focus = CaptureSettingsChooser.focusDiopters(options.ceilingDistanceM,
                facts.minimumFocusDistanceDiopters == null ? null : facts.minimumFocusDistanceDiopters.floatValue());
        if (focus != null && "uncalibrated".equals(facts.focusDistanceCalibration)) {
            notes.add("focus distance uncalibrated: the ceiling may be out of focus");
        }
        float[] toneCurve = facts.tonemapModes.contains("contrast_curve") ? new float[] {0f, 0f, 1f, 1f} : null;
        // Without a contrast curve, a known curve is the next best: the server undoes the sRGB preset exactly.
        boolean srgbPreset = toneCurve == null && facts.tonemapModes.contains("preset_curve");
        if (srgbPreset) {
            notes.add("no linear tone curve: the sRGB preset curve instead, which the server undoes");
        } else if (toneCurve == null) {
            notes.add("no linear tone curve: the server assumes one");
        }
        if (!facts.oisModes.isEmpty() && !facts.oisModes.contains("off")) {
            notes.add("optical stabilisation cannot be switched off: the principal point may move");
        }
        if (!facts.hasPerFrameControl()) {
            notes.add("SYNC_MAX_LATENCY " + syncMaxLatencyName(facts.syncMaxLatency) + ", not per-frame control: "
                    + "settings reach frames late, so each frame is taken as its capture result shows");
        }
        RequestSpec pose = new RequestSpec(RequestSpec.POSE, poseSettings.exposureNs, poseSettings.sensitivityIso,
                poseSettings.frameDurationNs, focus, crop, facts.oisModes.contains("off"), toneCurve, srgbPreset,
                facts.rotateAndCropModes != null && facts.rotateAndCropModes.contains("none"),
                facts.edgeModes.contains("off"), facts.noiseReductionModes.contains("off"), correctionOff);

        if (options.idExposureNs > 0 && options.beaconsInMap <= 1) {
            notes.add("one beacon in the map: no ID frames");
        }
        if (!options.wantsIdFrames()) {
            return new CapturePlan(output, pose, null, 0, notes, facts.maxFrameDurationNs, options.burstsPerSecond,
                    options.idBurstsPerSecond);
        }
        CaptureSettings idSettings;
        try {
            idSettings = IdCapturePlan.choose(ranges, options.idExposureNs, poseSettings,
                    CaptureProtocol.ID_BRIGHTNESS_FRACTION);
        } catch (UnsupportedCameraException e) {
            // The pose frames are still good: position without beacon IDs.
            notes.add(e.getMessage());
            return new CapturePlan(output, pose, null, 0, notes, facts.maxFrameDurationNs, options.burstsPerSecond,
                    options.idBurstsPerSecond);
        }
        notes.addAll(idSettings.notes);
        RequestSpec id = pose.withExposure(RequestSpec.ID, idSettings.exposureNs, idSettings.sensitivityIso,
                idSettings.frameDurationNs);
        return new CapturePlan(output, pose, id, CaptureProtocol.ID_BURST_FRAMES, notes, facts.maxFrameDurationNs,
                options.burstsPerSecond, options.idBurstsPerSecond);
    }

    /** The same plan without ID frames (for example when the results show no rolling-shutter skew). */
    public CapturePlan withoutIdFrames(String reason) {
        if (id == null) {
            return this;
        }
        List<String> more = new ArrayList<String>(settingsNotes);
        more.add(reason);
        return new CapturePlan(output, shortestPose(), null, 0, more, maxFrameDurationNs, poseAlonePerSecond,
                withIdFramesPerSecond);
    }

    /** The same plan repeating at most {@code perSecond} bursts a second (within the camera's frame durations). */
    public CapturePlan atBurstsPerSecond(double perSecond) {
        CaptureOptions.requireRate(perSecond);
        return new CapturePlan(output, shortestPose(), id, idFramesPerBurst, settingsNotes, maxFrameDurationNs,
                perSecond, perSecond);
    }

    private RequestSpec shortestPose() {
        return pose.withExposure(RequestSpec.POSE, pose.exposureNs, pose.sensitivityIso, poseMinimumFrameNs);
    }

    /**
     * The plan for still photos of a scene lit by the room (a printed calibration board): this plan's
     * output size, crop region, focus, tone curve and processing, so that the photos have the
     * positioning frames' intrinsics, but {@code exposureNs} and {@code iso} (both clamped to what
     * the camera offers) for the scene, and no ID frames, at {@link CaptureOptions#STILL_BURSTS_PER_S}
     * (a preview to aim by; the shutter takes the next frame). Its frames are "pose" frames.
     */
    public CapturePlan forStills(CameraFacts facts, long exposureNs, int iso) throws UnsupportedCameraException {
        CameraRanges ranges = ranges(facts, output);
        CaptureSettings s = CaptureSettingsChooser.choose(ranges, exposureNs);
        List<String> more = new ArrayList<String>(settingsNotes);
        more.addAll(s.notes);
        Integer clampedIso = null;
        if (ranges.sensitivityMinIso != null) {
            int max = ranges.sensitivityMaxIso == null ? iso : ranges.sensitivityMaxIso;
            clampedIso = Math.max(ranges.sensitivityMinIso, Math.min(max, iso));
            if (clampedIso != iso) {
                more.add("ISO " + iso + " clamped to " + clampedIso);
            }
        }
        RequestSpec still = pose.withExposure(RequestSpec.POSE, s.exposureNs, clampedIso, s.frameDurationNs);
        return new CapturePlan(output, still, null, 0, more, maxFrameDurationNs, CaptureOptions.STILL_BURSTS_PER_S,
                CaptureOptions.STILL_BURSTS_PER_S);
    }

    /**
     * The repeating burst in capture order: the pose request, then the ID requests, the last of
     * which lasts long enough to hold the burst to its rate.
     */
    public List<RequestSpec> burst() {
        List<RequestSpec> out = new ArrayList<RequestSpec>();
        out.add(pose);
        for (int i = 0; i < idFramesPerBurst; i++) {
            out.add(i == idFramesPerBurst - 1 ? lastId : id);
        }
        return Collections.unmodifiableList(out);
    }

    /** The spec of the request tagged {@code kind}, or null. */
    public RequestSpec spec(String kind) {
        if (RequestSpec.POSE.equals(kind)) {
            return pose;
        }
        return RequestSpec.ID.equals(kind) ? id : null;
    }

    /** SYNC_MAX_LATENCY as the docs name it: "per_frame_control", "unknown" or "N frames". */
    static String syncMaxLatencyName(int syncMaxLatency) {
        if (syncMaxLatency == CameraFacts.SYNC_PER_FRAME_CONTROL) {
            return "per_frame_control";
        }
        return syncMaxLatency == CameraFacts.SYNC_UNKNOWN ? "unknown" : syncMaxLatency + " frames";
    }

    static CameraRanges ranges(CameraFacts facts, PixelSize output) {
        return new CameraRanges(facts.has("manual_sensor"), facts.exposureTimeMinNs, facts.exposureTimeMaxNs,
                facts.sensitivityMin, facts.sensitivityMax, facts.maxFrameDurationNs, facts.minFrameDurationNs(output));
    }
}
