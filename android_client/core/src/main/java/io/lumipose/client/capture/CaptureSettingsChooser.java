package io.lumipose.client.capture;

import java.util.ArrayList;
import java.util.List;

/**
 * Chooses the manual capture values from the advertised ranges (paper Section III-B: minimum
 * sensitivity and 0.01 s exposure, so the panel's edge is sharp and the room stays dark).
 * The short exposure for reading a beacon's VLC code is a parameter: the VLC work settles it.
 */
public final class CaptureSettingsChooser {
    /** The paper's exposure for positioning frames: 10 ms. */
    public static final long POSITION_EXPOSURE_NS = 10_000_000L;
    /** Default short exposure for beacon-ID (VLC) frames: 1/8000 s, so a row sees a fraction of a code bit. */
    public static final long DEFAULT_ID_EXPOSURE_NS = 125_000L;

    private CaptureSettingsChooser() {
    }

    /**
     * {@code LENS_FOCUS_DISTANCE} for a panel at {@code distanceM}: diopters (1 / m), no nearer than
     * the lens can focus. Null for a fixed-focus lens ({@code LENS_INFO_MINIMUM_FOCUS_DISTANCE} 0 or absent).
     */
    public static Float focusDiopters(double distanceM, Float minimumFocusDistanceDiopters) {
        if (!(distanceM > 0)) {
            throw new IllegalArgumentException("focus distance must be > 0 m, got " + distanceM);
        }
        if (minimumFocusDistanceDiopters == null || minimumFocusDistanceDiopters <= 0f) {
            return null;
        }
        return (float) Math.min(1.0 / distanceM, minimumFocusDistanceDiopters);
    }

    /**
     * @param ranges           what the camera advertises
     * @param targetExposureNs wanted exposure, ns (for example {@link #POSITION_EXPOSURE_NS})
     * @throws UnsupportedCameraException without MANUAL_SENSOR or an exposure range
     */
    public static CaptureSettings choose(CameraRanges ranges, long targetExposureNs) throws UnsupportedCameraException {
        if (targetExposureNs <= 0) {
            throw new IllegalArgumentException("targetExposureNs must be > 0, got " + targetExposureNs);
        }
        if (!ranges.manualSensor) {
            throw new UnsupportedCameraException("This camera lacks the MANUAL_SENSOR capability: exposure and ISO "
                    + "cannot be fixed, so the beacon's edges cannot be measured. Choose another camera.");
        }
        if (ranges.exposureMinNs == null) {
            throw new UnsupportedCameraException("This camera advertises no SENSOR_INFO_EXPOSURE_TIME_RANGE, "
                    + "so the exposure cannot be set.");
        }
        List<String> notes = new ArrayList<String>();
        long exposureNs = Math.max(ranges.exposureMinNs, Math.min(ranges.exposureMaxNs, targetExposureNs));
        if (exposureNs != targetExposureNs) {
            notes.add("exposure " + targetExposureNs + " ns clamped to " + exposureNs + " ns (range "
                    + ranges.exposureMinNs + ".." + ranges.exposureMaxNs + ")");
        }
        Integer iso = ranges.sensitivityMinIso;
        if (iso == null) {
            notes.add("no SENSOR_INFO_SENSITIVITY_RANGE: ISO left to the device");
        }
        // A frame cannot be shorter than its exposure nor than the stream allows at this size.
        long frameDurationNs = Math.max(exposureNs, ranges.streamMinFrameDurationNs);
        if (ranges.maxFrameDurationNs != null && frameDurationNs > ranges.maxFrameDurationNs) {
            notes.add("frame duration " + frameDurationNs + " ns clamped to SENSOR_INFO_MAX_FRAME_DURATION "
                    + ranges.maxFrameDurationNs + " ns");
            frameDurationNs = ranges.maxFrameDurationNs;
        }
        return new CaptureSettings(exposureNs, iso, frameDurationNs, notes);
    }
}
