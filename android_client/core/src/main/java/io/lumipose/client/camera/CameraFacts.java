package io.lumipose.client.camera;

import java.util.ArrayList;
import java.util.Collections;
import java.util.List;

import org.json.JSONArray;
import org.json.JSONObject;

import io.lumipose.client.json.ContractException;
import io.lumipose.client.json.Json;
import io.lumipose.client.sensor.LensFacing;

/**
 * Everything of one camera's {@code CameraCharacteristics} the app uses, as plain values, so the
 * planning and the maths run (and are tested) without Android. The JSON form is docs/android.md's
 * {@code CameraFacts}: Camera2's key names in lower snake case, rectangles as [left, top, width,
 * height], enums as lower-case names. Null (or an empty list) where the device does not report a key.
 */
public final class CameraFacts {
    /** {@code SYNC_MAX_LATENCY}'s two named values; any other value is a frame count. */
    public static final int SYNC_PER_FRAME_CONTROL = 0;
    public static final int SYNC_UNKNOWN = -1;

    public final String cameraId;
    /** "front", "back" or "external". */
    public final String lensFacing;
    public final int sensorOrientationDeg;
    public final List<String> capabilities;
    /** {@link #SYNC_PER_FRAME_CONTROL}, {@link #SYNC_UNKNOWN} or a number of frames. */
    public final int syncMaxLatency;
    /** "realtime" or "unknown" (then sensor timestamps are not comparable to sensor events'). */
    public final String timestampSource;
    public final ArrayRect activeArray;
    /** Null when not reported (then it is taken to equal the active array). */
    public final ArrayRect preCorrectionActiveArray;
    public final PixelSize pixelArray;
    public final double physicalWidthMm;
    public final double physicalHeightMm;
    private final double[] availableFocalLengthsMm;
    private final double[] lensIntrinsicCalibration;
    private final double[] lensDistortion;
    private final double[] lensRadialDistortion;
    /** 0 or null: fixed focus. */
    public final Double minimumFocusDistanceDiopters;
    /** "uncalibrated", "approximate", "calibrated" or null. */
    public final String focusDistanceCalibration;
    public final List<String> oisModes;
    public final List<String> tonemapModes;
    public final Integer tonemapMaxCurvePoints;
    public final List<String> edgeModes;
    public final List<String> noiseReductionModes;
    public final List<String> distortionCorrectionModes;
    /** Null before API 30 (the key does not exist). */
    public final List<String> rotateAndCropModes;
    private final double[] zoomRatioRange;
    public final Long exposureTimeMinNs;
    public final Long exposureTimeMaxNs;
    public final Integer sensitivityMin;
    public final Integer sensitivityMax;
    public final Long maxFrameDurationNs;
    public final List<YuvOutput> yuvOutputs;

    /** One YUV_420_888 output size and its minimum frame duration (0 when unknown). */
    public static final class YuvOutput {
        public final PixelSize size;
        public final long minFrameDurationNs;

        public YuvOutput(PixelSize size, long minFrameDurationNs) {
            if (minFrameDurationNs < 0) {
                throw new IllegalArgumentException("minimum frame duration must be >= 0 ns, got " + minFrameDurationNs);
            }
            this.size = size;
            this.minFrameDurationNs = minFrameDurationNs;
        }
    }

    private CameraFacts(Builder b) {
        cameraId = b.cameraId;
        lensFacing = require("lens_facing", b.lensFacing);
        if (!"front".equals(lensFacing) && !"back".equals(lensFacing) && !"external".equals(lensFacing)) {
            throw new ContractException("lens_facing", "must be front, back or external, got '" + lensFacing + "'");
        }
        if (b.sensorOrientationDeg % 90 != 0 || b.sensorOrientationDeg < 0 || b.sensorOrientationDeg >= 360) {
            throw new ContractException("sensor_orientation", "must be 0, 90, 180 or 270, got " + b.sensorOrientationDeg);
        }
        sensorOrientationDeg = b.sensorOrientationDeg;
        capabilities = names(b.capabilities);
        if (b.syncMaxLatency < SYNC_UNKNOWN) {
            throw new ContractException("sync_max_latency", "must be per_frame_control, unknown or a frame count, got "
                    + b.syncMaxLatency);
        }
        syncMaxLatency = b.syncMaxLatency;
        timestampSource = b.timestampSource == null ? "unknown" : b.timestampSource;
        activeArray = require("active_array", b.activeArray);
        preCorrectionActiveArray = b.preCorrectionActiveArray;
        pixelArray = require("pixel_array", b.pixelArray);
        if (!(b.physicalWidthMm > 0) || !(b.physicalHeightMm > 0)) {
            throw new ContractException("physical_size_mm", "must be > 0, got " + b.physicalWidthMm + " x " + b.physicalHeightMm);
        }
        physicalWidthMm = b.physicalWidthMm;
        physicalHeightMm = b.physicalHeightMm;
        availableFocalLengthsMm = require("available_focal_lengths_mm", CameraJson.copy(b.availableFocalLengthsMm));
        if (availableFocalLengthsMm.length == 0) {
            throw new ContractException("available_focal_lengths_mm", "must hold at least one focal length");
        }
        for (double f : availableFocalLengthsMm) {
            if (!(f > 0)) {
                throw new ContractException("available_focal_lengths_mm", "must be > 0 mm, got " + f);
            }
        }
        lensIntrinsicCalibration = CameraJson.copy(b.lensIntrinsicCalibration);
        lensDistortion = CameraJson.copy(b.lensDistortion);
        lensRadialDistortion = CameraJson.copy(b.lensRadialDistortion);
        minimumFocusDistanceDiopters = b.minimumFocusDistanceDiopters;
        focusDistanceCalibration = b.focusDistanceCalibration;
        oisModes = names(b.oisModes);
        tonemapModes = names(b.tonemapModes);
        tonemapMaxCurvePoints = b.tonemapMaxCurvePoints;
        edgeModes = names(b.edgeModes);
        noiseReductionModes = names(b.noiseReductionModes);
        distortionCorrectionModes = names(b.distortionCorrectionModes);
        rotateAndCropModes = CameraJson.copy(b.rotateAndCropModes);
        if (b.zoomRatioRange != null && b.zoomRatioRange.length != 2) {
            throw new ContractException("zoom_ratio_range", "must hold [lower, upper]");
        }
        zoomRatioRange = CameraJson.copy(b.zoomRatioRange);
        exposureTimeMinNs = b.exposureTimeMinNs;
        exposureTimeMaxNs = b.exposureTimeMaxNs;
        sensitivityMin = b.sensitivityMin;
        sensitivityMax = b.sensitivityMax;
        maxFrameDurationNs = b.maxFrameDurationNs;
        yuvOutputs = Collections.unmodifiableList(new ArrayList<YuvOutput>(b.yuvOutputs));
    }

    private static <T> T require(String key, T value) {
        if (value == null) {
            throw new ContractException(key, "missing");
        }
        return value;
    }

    private static List<String> names(List<String> v) {
        return v == null ? Collections.<String>emptyList() : CameraJson.copy(v);
    }

    public static Builder builder() {
        return new Builder();
    }

    /** A builder holding this camera's values, to change a few. */
    public Builder toBuilder() {
        return fromJsonInto(toJson());
    }

    /** BACK or FRONT; null for an external camera, whose attitude to the phone is unknown. */
    public LensFacing facing() {
        if ("back".equals(lensFacing)) {
            return LensFacing.BACK;
        }
        return "front".equals(lensFacing) ? LensFacing.FRONT : null;
    }

    public boolean has(String capability) {
        return capabilities.contains(capability);
    }

    public boolean isLogicalMultiCamera() {
        return has("logical_multi_camera");
    }

    /** Settings apply on the very frame that asked for them. */
    public boolean hasPerFrameControl() {
        return syncMaxLatency == SYNC_PER_FRAME_CONTROL;
    }

    /** Sensor timestamps share the clock of sensor events (SystemClock.elapsedRealtimeNanos). */
    public boolean timestampsAreRealtime() {
        return "realtime".equals(timestampSource);
    }

    /** The array lens calibration and distortion refer to: the pre-correction array, else the active array. */
    public ArrayRect preCorrectionOrActive() {
        return preCorrectionActiveArray != null ? preCorrectionActiveArray : activeArray;
    }

    public double[] availableFocalLengthsMm() {
        return availableFocalLengthsMm.clone();
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

    public double[] zoomRatioRange() {
        return CameraJson.copy(zoomRatioRange);
    }

    /** Pixel pitch on the sensor, mm: the physical size covers the pixel array. */
    public double pixelPitchXMm() {
        return physicalWidthMm / pixelArray.width;
    }

    public double pixelPitchYMm() {
        return physicalHeightMm / pixelArray.height;
    }

    /** The output sizes as a list, for {@link OutputSizeChooser}. */
    public List<PixelSize> yuvSizes() {
        List<PixelSize> out = new ArrayList<PixelSize>();
        for (YuvOutput o : yuvOutputs) {
            out.add(o.size);
        }
        return out;
    }

    /** The stream's minimum frame duration at {@code size}, 0 when unknown. */
    public long minFrameDurationNs(PixelSize size) {
        for (YuvOutput o : yuvOutputs) {
            if (o.size.equals(size)) {
                return o.minFrameDurationNs;
            }
        }
        return 0;
    }

    public JSONObject toJson() {
        JSONObject o = new JSONObject();
        Json.put(o, "camera_id", cameraId);
        Json.put(o, "lens_facing", lensFacing);
        Json.put(o, "sensor_orientation", sensorOrientationDeg);
        Json.put(o, "capabilities", CameraJson.names(capabilities));
        Json.put(o, "sync_max_latency", syncMaxLatency == SYNC_PER_FRAME_CONTROL ? "per_frame_control"
                : syncMaxLatency == SYNC_UNKNOWN ? "unknown" : (Object) syncMaxLatency);
        Json.put(o, "timestamp_source", timestampSource);
        Json.put(o, "active_array", CameraJson.rect(activeArray));
        Json.put(o, "pre_correction_active_array", CameraJson.rect(preCorrectionActiveArray));
        Json.put(o, "pixel_array", CameraJson.ints(new long[] {pixelArray.width, pixelArray.height}));
        Json.put(o, "physical_size_mm", Json.array(new double[] {physicalWidthMm, physicalHeightMm}));
        Json.put(o, "available_focal_lengths_mm", Json.array(availableFocalLengthsMm));
        Json.put(o, "lens_intrinsic_calibration", CameraJson.doubles(lensIntrinsicCalibration));
        Json.put(o, "lens_distortion", CameraJson.doubles(lensDistortion));
        Json.put(o, "lens_radial_distortion", CameraJson.doubles(lensRadialDistortion));
        Json.put(o, "minimum_focus_distance_diopters", minimumFocusDistanceDiopters);
        Json.put(o, "focus_distance_calibration", focusDistanceCalibration);
        Json.put(o, "ois_modes", CameraJson.names(oisModes));
        Json.put(o, "tonemap_modes", CameraJson.names(tonemapModes));
        Json.put(o, "tonemap_max_curve_points", tonemapMaxCurvePoints);
        Json.put(o, "edge_modes", CameraJson.names(edgeModes));
        Json.put(o, "noise_reduction_modes", CameraJson.names(noiseReductionModes));
        Json.put(o, "distortion_correction_modes", CameraJson.names(distortionCorrectionModes));
        Json.put(o, "rotate_and_crop_modes", CameraJson.names(rotateAndCropModes));
        Json.put(o, "zoom_ratio_range", CameraJson.doubles(zoomRatioRange));
        Json.put(o, "exposure_time_range_ns", exposureTimeMinNs == null ? null
                : CameraJson.ints(new long[] {exposureTimeMinNs, exposureTimeMaxNs}));
        Json.put(o, "sensitivity_range", sensitivityMin == null ? null
                : CameraJson.ints(new long[] {sensitivityMin, sensitivityMax}));
        Json.put(o, "max_frame_duration_ns", maxFrameDurationNs);
        JSONArray outputs = new JSONArray();
        for (YuvOutput y : yuvOutputs) {
            outputs.put(CameraJson.ints(new long[] {y.size.width, y.size.height, y.minFrameDurationNs}));
        }
        Json.put(o, "yuv_outputs", outputs);
        return o;
    }

    /** @throws ContractException naming the key when a value is missing or malformed */
    public static CameraFacts fromJson(JSONObject o) {
        return fromJsonInto(o).build();
    }

    private static Builder fromJsonInto(JSONObject o) {
        Builder b = builder()
                .cameraId(Json.optString(o, "camera_id", "camera_id"))
                .lensFacing(CameraJson.optChoice(o, "lens_facing", "front", "back", "external"))
                .sensorOrientationDeg(Json.requireInt(o, "sensor_orientation", "sensor_orientation"))
                .capabilities(CameraJson.optNames(o, "capabilities"))
                .syncMaxLatency(syncMaxLatency(o))
                .timestampSource(CameraJson.optChoice(o, "timestamp_source", "realtime", "unknown"))
                .activeArray(CameraJson.requireRect(o, "active_array"))
                .preCorrectionActiveArray(CameraJson.optRect(o, "pre_correction_active_array"))
                .lensIntrinsicCalibration(Json.optDoubles(o, "lens_intrinsic_calibration", "lens_intrinsic_calibration", -1))
                .lensDistortion(Json.optDoubles(o, "lens_distortion", "lens_distortion", -1))
                .lensRadialDistortion(Json.optDoubles(o, "lens_radial_distortion", "lens_radial_distortion", -1))
                .minimumFocusDistanceDiopters(Json.optDouble(o, "minimum_focus_distance_diopters",
                        "minimum_focus_distance_diopters"))
                .focusDistanceCalibration(CameraJson.optChoice(o, "focus_distance_calibration",
                        "uncalibrated", "approximate", "calibrated"))
                .oisModes(CameraJson.optNames(o, "ois_modes"))
                .tonemapModes(CameraJson.optNames(o, "tonemap_modes"))
                .tonemapMaxCurvePoints(CameraJson.optInt(o, "tonemap_max_curve_points"))
                .edgeModes(CameraJson.optNames(o, "edge_modes"))
                .noiseReductionModes(CameraJson.optNames(o, "noise_reduction_modes"))
                .distortionCorrectionModes(CameraJson.optNames(o, "distortion_correction_modes"))
                .rotateAndCropModes(CameraJson.optNames(o, "rotate_and_crop_modes"))
                .zoomRatioRange(Json.optDoubles(o, "zoom_ratio_range", "zoom_ratio_range", 2))
                .maxFrameDurationNs(Json.optLong(o, "max_frame_duration_ns", "max_frame_duration_ns"));
        long[] pixelArray = CameraJson.optLongs(o, "pixel_array", 2);
        if (pixelArray == null) {
            throw new ContractException("pixel_array", "missing");
        }
        if (pixelArray[0] <= 0 || pixelArray[1] <= 0) {
            throw new ContractException("pixel_array", "must be positive, got " + pixelArray[0] + "x" + pixelArray[1]);
        }
        b.pixelArray(new PixelSize((int) pixelArray[0], (int) pixelArray[1]));
        double[] physical = Json.optDoubles(o, "physical_size_mm", "physical_size_mm", 2);
        if (physical == null) {
            throw new ContractException("physical_size_mm", "missing");
        }
        b.physicalSizeMm(physical[0], physical[1]);
        double[] focal = Json.optDoubles(o, "available_focal_lengths_mm", "available_focal_lengths_mm", -1);
        if (focal == null) {
            throw new ContractException("available_focal_lengths_mm", "missing");
        }
        b.availableFocalLengthsMm(focal);
        long[] exposure = CameraJson.optLongs(o, "exposure_time_range_ns", 2);
        if (exposure != null) {
            if (exposure[0] <= 0 || exposure[0] > exposure[1]) {
                throw new ContractException("exposure_time_range_ns", "must be a positive [lower, upper], got ["
                        + exposure[0] + ", " + exposure[1] + "]");
            }
            b.exposureTimeRangeNs(exposure[0], exposure[1]);
        }
        long[] sensitivity = CameraJson.optLongs(o, "sensitivity_range", 2);
        if (sensitivity != null) {
            if (sensitivity[0] <= 0 || sensitivity[0] > sensitivity[1] || sensitivity[1] > Integer.MAX_VALUE) {
                throw new ContractException("sensitivity_range", "must be a positive [lower, upper], got ["
                        + sensitivity[0] + ", " + sensitivity[1] + "]");
            }
            b.sensitivityRange((int) sensitivity[0], (int) sensitivity[1]);
        }
        List<JSONArray> outputs = outputs(o);
        for (int i = 0; i < outputs.size(); i++) {
            JSONObject wrapper = new JSONObject();
            Json.put(wrapper, "yuv_outputs[" + i + "]", outputs.get(i));
            long[] v = CameraJson.optLongs(wrapper, "yuv_outputs[" + i + "]", 3);
            if (v[0] <= 0 || v[1] <= 0 || v[2] < 0) {
                throw new ContractException("yuv_outputs[" + i + "]", "must be [w > 0, h > 0, min_frame_duration_ns >= 0]");
            }
            b.addYuvOutput(new PixelSize((int) v[0], (int) v[1]), v[2]);
        }
        return b;
    }

    private static int syncMaxLatency(JSONObject o) {
        Object v = o.opt("sync_max_latency");
        if (v == null || v == JSONObject.NULL || "unknown".equals(v)) {
            return SYNC_UNKNOWN;
        }
        if ("per_frame_control".equals(v)) {
            return SYNC_PER_FRAME_CONTROL;
        }
        if ((v instanceof Integer || v instanceof Long) && ((Number) v).longValue() > 0
                && ((Number) v).longValue() <= Integer.MAX_VALUE) {
            return ((Number) v).intValue();
        }
        throw new ContractException("sync_max_latency", "must be \"per_frame_control\", \"unknown\" or a frame count > 0, got " + v);
    }

    private static List<JSONArray> outputs(JSONObject o) {
        List<JSONArray> out = new ArrayList<JSONArray>();
        if (!Json.isPresent(o, "yuv_outputs")) {
            return out;
        }
        if (!(o.opt("yuv_outputs") instanceof JSONArray)) {
            throw new ContractException("yuv_outputs", "must be an array of [w, h, min_frame_duration_ns]");
        }
        JSONArray a = (JSONArray) o.opt("yuv_outputs");
        for (int i = 0; i < a.length(); i++) {
            if (!(a.opt(i) instanceof JSONArray)) {
                throw new ContractException("yuv_outputs[" + i + "]", "must be [w, h, min_frame_duration_ns]");
            }
            out.add((JSONArray) a.opt(i));
        }
        return out;
    }

    /** Builds {@link CameraFacts}; lens facing, sensor orientation, the arrays, physical size and focal lengths are required. */
    public static final class Builder {
        private String cameraId;
        private String lensFacing;
        private int sensorOrientationDeg;
        private List<String> capabilities;
        private int syncMaxLatency = SYNC_UNKNOWN;
        private String timestampSource;
        private ArrayRect activeArray;
        private ArrayRect preCorrectionActiveArray;
        private PixelSize pixelArray;
        private double physicalWidthMm;
        private double physicalHeightMm;
        private double[] availableFocalLengthsMm;
        private double[] lensIntrinsicCalibration;
        private double[] lensDistortion;
        private double[] lensRadialDistortion;
        private Double minimumFocusDistanceDiopters;
        private String focusDistanceCalibration;
        private List<String> oisModes;
        private List<String> tonemapModes;
        private Integer tonemapMaxCurvePoints;
        private List<String> edgeModes;
        private List<String> noiseReductionModes;
        private List<String> distortionCorrectionModes;
        private List<String> rotateAndCropModes;
        private double[] zoomRatioRange;
        private Long exposureTimeMinNs;
        private Long exposureTimeMaxNs;
        private Integer sensitivityMin;
        private Integer sensitivityMax;
        private Long maxFrameDurationNs;
        private final List<YuvOutput> yuvOutputs = new ArrayList<YuvOutput>();

        private Builder() {
        }

        public Builder cameraId(String v) {
            cameraId = v;
            return this;
        }

        /** "front", "back" or "external". */
        public Builder lensFacing(String v) {
            lensFacing = v;
            return this;
        }

        public Builder sensorOrientationDeg(int v) {
            sensorOrientationDeg = v;
            return this;
        }

        public Builder capabilities(List<String> v) {
            capabilities = v;
            return this;
        }

        /** {@link #SYNC_PER_FRAME_CONTROL}, {@link #SYNC_UNKNOWN} or a frame count. */
        public Builder syncMaxLatency(int v) {
            syncMaxLatency = v;
            return this;
        }

        public Builder timestampSource(String v) {
            timestampSource = v;
            return this;
        }

        public Builder activeArray(ArrayRect v) {
            activeArray = v;
            return this;
        }

        public Builder preCorrectionActiveArray(ArrayRect v) {
            preCorrectionActiveArray = v;
            return this;
        }

        public Builder pixelArray(PixelSize v) {
            pixelArray = v;
            return this;
        }

        public Builder physicalSizeMm(double width, double height) {
            physicalWidthMm = width;
            physicalHeightMm = height;
            return this;
        }

        public Builder availableFocalLengthsMm(double... v) {
            availableFocalLengthsMm = CameraJson.copy(v);
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

        public Builder minimumFocusDistanceDiopters(Double v) {
            minimumFocusDistanceDiopters = v;
            return this;
        }

        public Builder focusDistanceCalibration(String v) {
            focusDistanceCalibration = v;
            return this;
        }

        public Builder oisModes(List<String> v) {
            oisModes = v;
            return this;
        }

        public Builder tonemapModes(List<String> v) {
            tonemapModes = v;
            return this;
        }

        public Builder tonemapMaxCurvePoints(Integer v) {
            tonemapMaxCurvePoints = v;
            return this;
        }

        public Builder edgeModes(List<String> v) {
            edgeModes = v;
            return this;
        }

        public Builder noiseReductionModes(List<String> v) {
            noiseReductionModes = v;
            return this;
        }

        public Builder distortionCorrectionModes(List<String> v) {
            distortionCorrectionModes = v;
            return this;
        }

        public Builder rotateAndCropModes(List<String> v) {
            rotateAndCropModes = v;
            return this;
        }

        public Builder zoomRatioRange(double[] v) {
            zoomRatioRange = CameraJson.copy(v);
            return this;
        }

        public Builder exposureTimeRangeNs(long lower, long upper) {
            exposureTimeMinNs = lower;
            exposureTimeMaxNs = upper;
            return this;
        }

        public Builder sensitivityRange(int lower, int upper) {
            sensitivityMin = lower;
            sensitivityMax = upper;
            return this;
        }

        public Builder maxFrameDurationNs(Long v) {
            maxFrameDurationNs = v;
            return this;
        }

        public Builder addYuvOutput(PixelSize size, long minFrameDurationNs) {
            yuvOutputs.add(new YuvOutput(size, minFrameDurationNs));
            return this;
        }

        public Builder clearYuvOutputs() {
            yuvOutputs.clear();
            return this;
        }

        public CameraFacts build() {
            return new CameraFacts(this);
        }
    }
}
