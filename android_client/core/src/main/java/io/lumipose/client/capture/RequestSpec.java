package io.lumipose.client.capture;

import io.lumipose.client.camera.ArrayRect;

/**
 * What one repeating capture request sets, in Camera2's terms; the app turns it into a
 * CaptureRequest without deciding anything. Null (or false) means "leave the key alone".
 */
public final class RequestSpec {
    public static final String POSE = "pose";
    public static final String ID = "id";

    /** "pose" or "id": the request's tag. */
    public final String kind;
    public final long exposureNs;
    /** Null when the camera has no sensitivity range. */
    public final Integer sensitivityIso;
    public final long frameDurationNs;
    /** {@code LENS_FOCUS_DISTANCE}, diopters; null for a fixed-focus lens. */
    public final Float focusDiopters;
    /**
     * {@code SCALER_CROP_REGION} in its own coordinates (relative to the active array, or to the
     * pre-correction array when distortion correction is off): the source rectangle the maths assumes.
     */
    public final ArrayRect cropRegion;
    public final boolean oisOff;
    /** Linear {@code TONEMAP_CURVE} points [in, out, in, out, ...]; null without CONTRAST_CURVE mode. */
    private final float[] toneCurve;
    /**
     * {@code TONEMAP_MODE_PRESET_CURVE} with {@code TONEMAP_PRESET_CURVE_SRGB}, the fallback where there is no
     * contrast curve: a known curve, which the server undoes. Never together with {@link #toneCurve()}.
     */
    public final boolean srgbPreset;
    public final boolean rotateAndCropNone;
    public final boolean edgeOff;
    public final boolean noiseReductionOff;
    public final boolean distortionCorrectionOff;

    public RequestSpec(String kind, long exposureNs, Integer sensitivityIso, long frameDurationNs, Float focusDiopters,
                       ArrayRect cropRegion, boolean oisOff, float[] toneCurve, boolean srgbPreset,
                       boolean rotateAndCropNone, boolean edgeOff, boolean noiseReductionOff,
                       boolean distortionCorrectionOff) {
        if (!POSE.equals(kind) && !ID.equals(kind)) {
            throw new IllegalArgumentException("kind must be \"pose\" or \"id\", got " + kind);
        }
        if (exposureNs <= 0 || frameDurationNs < exposureNs) {
            throw new IllegalArgumentException("need 0 < exposure <= frame duration, got " + exposureNs + " ns, "
                    + frameDurationNs + " ns");
        }
        if (cropRegion == null) {
            throw new IllegalArgumentException("the crop region is required: the intrinsics depend on it");
        }
        if (toneCurve != null && (toneCurve.length < 4 || toneCurve.length % 2 != 0)) {
            throw new IllegalArgumentException("a tone curve needs at least two (in, out) points");
        }
        if (toneCurve != null && srgbPreset) {
            throw new IllegalArgumentException("one tone map mode: a contrast curve or the sRGB preset, not both");
        }
        this.kind = kind;
        this.exposureNs = exposureNs;
        this.sensitivityIso = sensitivityIso;
        this.frameDurationNs = frameDurationNs;
        this.focusDiopters = focusDiopters;
        this.cropRegion = cropRegion;
        this.oisOff = oisOff;
        this.toneCurve = toneCurve == null ? null : toneCurve.clone();
        this.srgbPreset = srgbPreset;
        this.rotateAndCropNone = rotateAndCropNone;
        this.edgeOff = edgeOff;
        this.noiseReductionOff = noiseReductionOff;
        this.distortionCorrectionOff = distortionCorrectionOff;
    }

    public float[] toneCurve() {
        return toneCurve == null ? null : toneCurve.clone();
    }

    public boolean linearToneCurve() {
        return toneCurve != null;
    }

    /** The same request with another kind, exposure, ISO and frame duration (the ID frames share the rest). */
    public RequestSpec withExposure(String kind, long exposureNs, Integer sensitivityIso, long frameDurationNs) {
        return new RequestSpec(kind, exposureNs, sensitivityIso, frameDurationNs, focusDiopters, cropRegion, oisOff,
                toneCurve, srgbPreset, rotateAndCropNone, edgeOff, noiseReductionOff, distortionCorrectionOff);
    }
}
