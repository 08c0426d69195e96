package io.lumipose.client.camera;

import org.json.JSONObject;

import io.lumipose.client.json.ContractException;
import io.lumipose.client.json.Json;

/**
 * What one {@code TotalCaptureResult} says was actually used for a frame (docs/android.md's
 * {@code FrameResult}). Only the timestamp is required; everything else is null where the device
 * does not report it. On a logical multi-camera the lens values are the physical lens in use.
 */
public final class FrameResult {
    /** {@code SENSOR_TIMESTAMP}: matches the frame's Image and the gravity sample. */
    public final long timestampNs;
    /** The request's tag, "pose" or "id"; null when untagged. Says what was asked, not what was done. */
    public final String request;
    public final Long exposureNs;
    public final Integer sensitivityIso;
    public final Long frameDurationNs;
    public final Long rollingShutterSkewNs;
    public final Double focalLengthMm;
    private final double[] lensIntrinsicCalibration;
    private final double[] lensDistortion;
    private final double[] lensRadialDistortion;
    public final ArrayRect cropRegion;
    public final Double zoomRatio;
    /** "off" / "on". */
    public final String oisMode;
    /** "contrast_curve", "fast", "preset_curve", ... */
    public final String tonemapMode;
    /** {@code TONEMAP_PRESET_CURVE}, "srgb" or "rec709"; meaningful when {@link #tonemapMode} is "preset_curve". */
    public final String tonemapPresetCurve;
    public final Double focusDistanceDiopters;
    /** "none", "90", ... or null (before API 30). */
    public final String rotateAndCrop;
    /** "off", "fast", ... or null. */
    public final String distortionCorrectionMode;

    private FrameResult(Builder b) {
        if (b.request != null && !"pose".equals(b.request) && !"id".equals(b.request)) {
            throw new ContractException("request", "must be \"pose\", \"id\" or null, got '" + b.request + "'");
        }
        timestampNs = b.timestampNs;
        request = b.request;
        exposureNs = b.exposureNs;
        sensitivityIso = b.sensitivityIso;
        frameDurationNs = b.frameDurationNs;
        rollingShutterSkewNs = b.rollingShutterSkewNs;
        focalLengthMm = b.focalLengthMm;
        lensIntrinsicCalibration = CameraJson.copy(b.lensIntrinsicCalibration);
        lensDistortion = CameraJson.copy(b.lensDistortion);
        lensRadialDistortion = CameraJson.copy(b.lensRadialDistortion);
        cropRegion = b.cropRegion;
        zoomRatio = b.zoomRatio;
        oisMode = b.oisMode;
        tonemapMode = b.tonemapMode;
        tonemapPresetCurve = b.tonemapPresetCurve;
        focusDistanceDiopters = b.focusDistanceDiopters;
        rotateAndCrop = b.rotateAndCrop;
        distortionCorrectionMode = b.distortionCorrectionMode;
    }

    public static Builder builder(long timestampNs) {
        return new Builder(timestampNs);
    }

    /** A builder holding this result's values, to change a few. */
    public Builder toBuilder() {
        return fromJsonInto(toJson());
    }

    public double[] lensIntrinsicCalibration() {
        return CameraJson.copy(lensIntrinsicCalibration);
    }

    public double[] lensDistortion() {
        return CameraJson.copy(lensDistortion);
    }

    public double[] lensRadialDistortion() {
        return CameraJson.copy(lensRadialDistortion);
    }

    public JSONObject toJson() {
        JSONObject o = new JSONObject();
        Json.put(o, "sensor_timestamp_ns", timestampNs);
        Json.put(o, "request", request);
        Json.put(o, "sensor_exposure_time_ns", exposureNs);
        Json.put(o, "sensor_sensitivity", sensitivityIso);
        Json.put(o, "sensor_frame_duration_ns", frameDurationNs);
        Json.put(o, "sensor_rolling_shutter_skew_ns", rollingShutterSkewNs);
        Json.put(o, "lens_focal_length_mm", focalLengthMm);
        Json.put(o, "lens_intrinsic_calibration", CameraJson.doubles(lensIntrinsicCalibration));
        Json.put(o, "lens_distortion", CameraJson.doubles(lensDistortion));
        Json.put(o, "lens_radial_distortion", CameraJson.doubles(lensRadialDistortion));
        Json.put(o, "scaler_crop_region", CameraJson.rect(cropRegion));
        Json.put(o, "control_zoom_ratio", zoomRatio);
        Json.put(o, "lens_optical_stabilization_mode", oisMode);
        Json.put(o, "tonemap_mode", tonemapMode);
        Json.put(o, "tonemap_preset_curve", tonemapPresetCurve);
        Json.put(o, "lens_focus_distance_diopters", focusDistanceDiopters);
        Json.put(o, "scaler_rotate_and_crop", rotateAndCrop);
        Json.put(o, "distortion_correction_mode", distortionCorrectionMode);
        return o;
    }

    /** @throws ContractException naming the key when the timestamp is missing or a value is malformed */
    public static FrameResult fromJson(JSONObject o) {
        return fromJsonInto(o).build();
    }

    private static Builder fromJsonInto(JSONObject o) {
        Long timestamp = Json.optLong(o, "sensor_timestamp_ns", "sensor_timestamp_ns");
        if (timestamp == null) {
            throw new ContractException("sensor_timestamp_ns", "missing");
        }
        return builder(timestamp)
                .request(Json.optString(o, "request", "request"))
                .exposureNs(Json.optLong(o, "sensor_exposure_time_ns", "sensor_exposure_time_ns"))
                .sensitivityIso(CameraJson.optInt(o, "sensor_sensitivity"))
                .frameDurationNs(Json.optLong(o, "sensor_frame_duration_ns", "sensor_frame_duration_ns"))
                .rollingShutterSkewNs(Json.optLong(o, "sensor_rolling_shutter_skew_ns", "sensor_rolling_shutter_skew_ns"))
                .focalLengthMm(Json.optDouble(o, "lens_focal_length_mm", "lens_focal_length_mm"))
                .lensIntrinsicCalibration(Json.optDoubles(o, "lens_intrinsic_calibration", "lens_intrinsic_calibration", -1))
                .lensDistortion(Json.optDoubles(o, "lens_distortion", "lens_distortion", -1))
                .lensRadialDistortion(Json.optDoubles(o, "lens_radial_distortion", "lens_radial_distortion", -1))
                .cropRegion(CameraJson.optRect(o, "scaler_crop_region"))
                .zoomRatio(Json.optDouble(o, "control_zoom_ratio", "control_zoom_ratio"))
                .oisMode(Json.optString(o, "lens_optical_stabilization_mode", "lens_optical_stabilization_mode"))
                .tonemapMode(Json.optString(o, "tonemap_mode", "tonemap_mode"))
                .tonemapPresetCurve(Json.optString(o, "tonemap_preset_curve", "tonemap_preset_curve"))
                .focusDistanceDiopters(Json.optDouble(o, "lens_focus_distance_diopters", "lens_focus_distance_diopters"))
                .rotateAndCrop(Json.optString(o, "scaler_rotate_and_crop", "scaler_rotate_and_crop"))
                .distortionCorrectionMode(Json.optString(o, "distortion_correction_mode", "distortion_correction_mode"));
    }

    /** Builds a {@link FrameResult}; only the timestamp is required. */
    public static final class Builder {
        private final long timestampNs;
        private String request;
        private Long exposureNs;
        private Integer sensitivityIso;
        private Long frameDurationNs;
        private Long rollingShutterSkewNs;
        private Double focalLengthMm;
        private double[] lensIntrinsicCalibration;
        private double[] lensDistortion;
        private double[] lensRadialDistortion;
        private ArrayRect cropRegion;
        private Double zoomRatio;
        private String oisMode;
        private String tonemapMode;
        private String tonemapPresetCurve;
        private Double focusDistanceDiopters;
        private String rotateAndCrop;
        private String distortionCorrectionMode;

        private Builder(long timestampNs) {
            this.timestampNs = timestampNs;
        }

        public Builder request(String v) {
            request = v;
            return this;
        }

        public Builder exposureNs(Long v) {
            exposureNs = v;
            return this;
        }

        public Builder sensitivityIso(Integer v) {
            sensitivityIso = v;
            return this;
        }

        public Builder frameDurationNs(Long v) {
            frameDurationNs = v;
            return this;
        }

        public Builder rollingShutterSkewNs(Long v) {
            rollingShutterSkewNs = v;
            return this;
        }

        public Builder focalLengthMm(Double v) {
            focalLengthMm = v;
            return this;
        }

        public Builder lensIntrinsicCalibration(double[] v) {
            lensIntrinsicCalibration = CameraJson.copy(v);
            return this;
        }

        public Builder lensDistortion(double[] v) {
            lensDistortion = CameraJson.copy(v);
            return this;
        }

        public Builder lensRadialDistortion(double[] v) {
            lensRadialDistortion = CameraJson.copy(v);
            return this;
        }

        public Builder cropRegion(ArrayRect v) {
            cropRegion = v;
            return this;
        }

        public Builder zoomRatio(Double v) {
            zoomRatio = v;
            return this;
        }

        public Builder oisMode(String v) {
            oisMode = v;
            return this;
        }

        public Builder tonemapMode(String v) {
            tonemapMode = v;
            return this;
        }

        public Builder tonemapPresetCurve(String v) {
            tonemapPresetCurve = v;
            return this;
        }

        public Builder focusDistanceDiopters(Double v) {
            focusDistanceDiopters = v;
            return this;
        }

        public Builder rotateAndCrop(String v) {
            rotateAndCrop = v;
            return this;
        }

        public Builder distortionCorrectionMode(String v) {
            distortionCorrectionMode = v;
            return this;
        }

        public FrameResult build() {
            return new FrameResult(this);
        }
    }
}
