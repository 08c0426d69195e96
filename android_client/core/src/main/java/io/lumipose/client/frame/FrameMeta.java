package io.lumipose.client.frame;

import java.util.Arrays;
import java.util.HashSet;
import java.util.Set;

import org.json.JSONObject;

import io.lumipose.client.camera.Intrinsics;
import io.lumipose.client.contract.ContractRanges;
import io.lumipose.client.json.ContractException;
import io.lumipose.client.json.Json;

/**
 * The contract's frame JSON ({@code lumipose.frame/1}) that travels with every frame.
 * Fields the client does not know are kept and written back, as the contract asks.
 * Every number is checked against its range in the contract ({@link ContractRanges}): a frame the
 * server would refuse is refused here, naming the field.
 */
public final class FrameMeta {
    public static final String SCHEMA = "lumipose.frame/1";
    private static final Set<String> KNOWN = new HashSet<String>(Arrays.asList("schema", "format", "width", "height",
            "row_stride", "camera", "exposure_s", "iso", "rolling_shutter_skew_s", "timestamp_ns", "heading_deg",
            "compass_bearing_deg", "gravity_camera", "angular_velocity_camera_dps", "frame_kind", "crop",
            "tone_curve"));
    private static final Set<String> KNOWN_CAMERA = new HashSet<String>(Arrays.asList("fx", "fy", "cx", "cy",
            "distortion", "pixel_size_m", "focal_length_m", "device", "profile"));
    private static final Set<String> TONE_CURVES = new HashSet<String>(Arrays.asList("linear", "srgb", "device"));

    public final String format;
    public final int width;
    public final int height;
    public final int rowStride;
    /** Null when the camera is given by a device profile. */
    public final Intrinsics camera;
    /** Device profile id, null when intrinsics are given. */
    public final String cameraProfile;
    public final Double exposureS;
    public final Double iso;
    public final Double rollingShutterSkewS;
    public final Long timestampNs;
    public final Double headingDeg;
    /** Compass bearing (deg clockwise from north) of the image's +x laid level; null when not measured. */
    public final Double compassBearingDeg;
    private final double[] gravityCamera;
    private final double[] angularVelocityCameraDps;
    /** "pose" or "id" (a short-exposure VLC frame); null = not stated, which the contract reads as pose. */
    public final String frameKind;
    /** Where these pixels lie in the full frame the camera describes; null for a whole frame. */
    public final Crop crop;
    /** "linear", "srgb" (the preset, which the server undoes) or "device": the curve applied; null = not stated. */
    public final String toneCurve;
    private final String extrasJson;
    private final String cameraExtrasJson;

    private FrameMeta(Builder b) {
        ContractRanges.SIDE_PX.check("width", b.width);
        ContractRanges.SIDE_PX.check("height", b.height);
        int stride = b.rowStride == null ? b.width : b.rowStride;
        ContractRanges.ROW_STRIDE.check("row_stride", stride);
        if ("Y8".equals(b.format) && stride < b.width) {
            throw new ContractException("row_stride", "must be >= width " + b.width + ", got " + stride);
        }
        if ((b.camera == null) == (b.cameraProfile == null)) {
            throw new ContractException("camera", "give either intrinsics or a device profile");
        }
        if (b.crop != null) {
            b.crop.checkHolds(b.width, b.height);
        }
        if (b.camera != null) {
            checkCamera(b.camera, b.crop == null ? b.width : b.crop.fullWidth,
                    b.crop == null ? b.height : b.crop.fullHeight);
        }
        ContractRanges.EXPOSURE_S.check("exposure_s", b.exposureS);
        ContractRanges.ISO.check("iso", b.iso);
        ContractRanges.ROLLING_SHUTTER_SKEW_S.check("rolling_shutter_skew_s", b.rollingShutterSkewS);
        ContractRanges.checkTimestampNs("timestamp_ns", b.timestampNs);
        ContractRanges.ANGLE_DEG.check("heading_deg", b.headingDeg);
        ContractRanges.ANGLE_DEG.check("compass_bearing_deg", b.compassBearingDeg);
        if (b.frameKind != null && !"pose".equals(b.frameKind) && !"id".equals(b.frameKind)) {
            throw new ContractException("frame_kind", "must be 'pose' or 'id', got '" + b.frameKind + "'");
        }
        if (b.toneCurve != null && !TONE_CURVES.contains(b.toneCurve)) {
            throw new ContractException("tone_curve",
                    "must be 'linear', 'srgb' or 'device', got '" + b.toneCurve + "'");
        }
        if (b.gravityCamera != null && b.gravityCamera.length != 3) {
            throw new ContractException("gravity_camera", "must hold 3 numbers");
        }
        ContractRanges.checkGravity("gravity_camera", b.gravityCamera);
        if (b.angularVelocityCameraDps != null && b.angularVelocityCameraDps.length != 3) {
            throw new ContractException("angular_velocity_camera_dps", "must hold 3 numbers");
        }
        ContractRanges.ANGULAR_RATE_DPS.checkEach("angular_velocity_camera_dps", b.angularVelocityCameraDps);
        this.format = b.format;
        this.width = b.width;
        this.height = b.height;
        this.rowStride = stride;
        this.camera = b.camera;
        this.cameraProfile = b.cameraProfile;
        this.exposureS = b.exposureS;
        this.iso = b.iso;
        this.rollingShutterSkewS = b.rollingShutterSkewS;
        this.timestampNs = b.timestampNs;
        this.headingDeg = b.headingDeg;
        this.compassBearingDeg = b.compassBearingDeg;
        this.gravityCamera = b.gravityCamera == null ? null : b.gravityCamera.clone();
        this.angularVelocityCameraDps = b.angularVelocityCameraDps == null ? null
                : b.angularVelocityCameraDps.clone();
        this.frameKind = b.frameKind;
        this.crop = b.crop;
        this.toneCurve = b.toneCurve;
        this.extrasJson = b.extras.toString();
        this.cameraExtrasJson = b.cameraExtras.toString();
    }

    private static void checkCamera(Intrinsics k, int fullWidth, int fullHeight) {
        ContractRanges.FOCAL_PX.check("camera.fx", k.fx);
        ContractRanges.FOCAL_PX.check("camera.fy", k.fy);
        ContractRanges.checkPrincipalPoint("camera.cx", k.cx, fullWidth);
        ContractRanges.checkPrincipalPoint("camera.cy", k.cy, fullHeight);
        double[] d = k.distortion();
        if (d.length != 0 && d.length != 4 && d.length != 5 && d.length != 8) {
            throw new ContractException("camera.distortion", "must hold 0, 4, 5 or 8 OpenCV coefficients, got "
                    + d.length);
        }
        ContractRanges.DISTORTION.checkEach("camera.distortion", d);
        ContractRanges.PIXEL_SIZE_M.check("camera.pixel_size_m", k.pixelSizeM);
        ContractRanges.FOCAL_LENGTH_M.check("camera.focal_length_m", k.focalLengthM);
    }

    public static Builder builder(int width, int height) {
        return new Builder(width, height);
    }

    /** Width of the full frame the camera's intrinsics describe: the crop's, or this frame's. */
    /** True when the pixels are a window of a larger frame (the contract's {@code crop}). */
    public boolean isWindow() {
        return crop != null;
    }

    public int fullWidth() {
        return crop == null ? width : crop.fullWidth;
    }

    /** Height of the full frame the camera's intrinsics describe: the crop's, or this frame's. */
    public int fullHeight() {
        return crop == null ? height : crop.fullHeight;
    }

    /**
     * This frame cut to the window {@code width x height} at ({@code x}, {@code y}) of its own pixels,
     * packed (row_stride = width); the intrinsics still describe the full frame, as the contract's
     * {@code crop} asks.
     *
     * @param levelsDn the whole frame's [background, plateau] grey levels by the contract's coarse
     *                 rule ({@code crop.levels_dn}), or null; a window of a window keeps its frame's
     */
    public FrameMeta window(int x, int y, int width, int height, double[] levelsDn) {
        int offsetX = crop == null ? 0 : crop.x;
        int offsetY = crop == null ? 0 : crop.y;
        double[] levels = crop != null && crop.levelsDn != null ? crop.levelsDn : levelsDn;
        JSONObject o = toJson();
        Json.put(o, "width", width);
        Json.put(o, "height", height);
        Json.put(o, "row_stride", width);
        Json.put(o, "crop", new Crop(offsetX + x, offsetY + y, fullWidth(), fullHeight(), levels).toJson());
        return fromJson(o);
    }

    /** Gravity (pointing down) in the camera frame, or null. */
    public double[] gravityCamera() {
        return gravityCamera == null ? null : gravityCamera.clone();
    }

    /** The phone's rotation rate over the readout in the camera frame, deg/s, or null. */
    public double[] angularVelocityCameraDps() {
        return angularVelocityCameraDps == null ? null : angularVelocityCameraDps.clone();
    }

    /** Bytes the frame file or upload body must hold. */
    public long frameBytes() {
        if ("Y8".equals(format)) {
            return (long) rowStride * height;
        }
        if ("NV21".equals(format) || "I420".equals(format)) {
            return (long) rowStride * height * 3 / 2;
        }
        return -1;
    }

    public JSONObject toJson() {
        JSONObject o = Json.parseObject(extrasJson, "extras");
        Json.put(o, "schema", SCHEMA);
        Json.put(o, "format", format);
        Json.put(o, "width", width);
        Json.put(o, "height", height);
        Json.put(o, "row_stride", rowStride);
        JSONObject cam = Json.parseObject(cameraExtrasJson, "camera extras");
        if (camera != null) {
            Json.put(cam, "fx", camera.fx);
            Json.put(cam, "fy", camera.fy);
            Json.put(cam, "cx", camera.cx);
            Json.put(cam, "cy", camera.cy);
            Json.put(cam, "distortion", Json.array(camera.distortion()));
            putIfSet(cam, "pixel_size_m", camera.pixelSizeM);
            putIfSet(cam, "focal_length_m", camera.focalLengthM);
            putIfSet(cam, "device", camera.device);
        } else {
            Json.put(cam, "profile", cameraProfile);
        }
        Json.put(o, "camera", cam);
        putIfSet(o, "exposure_s", exposureS);
        putIfSet(o, "iso", iso);
        putIfSet(o, "rolling_shutter_skew_s", rollingShutterSkewS);
        putIfSet(o, "timestamp_ns", timestampNs);
        putIfSet(o, "heading_deg", headingDeg);
        putIfSet(o, "compass_bearing_deg", compassBearingDeg);
        if (gravityCamera != null) {
            Json.put(o, "gravity_camera", Json.array(gravityCamera));
        }
        if (angularVelocityCameraDps != null) {
            Json.put(o, "angular_velocity_camera_dps", Json.array(angularVelocityCameraDps));
        }
        putIfSet(o, "frame_kind", frameKind);
        if (crop != null) {
            Json.put(o, "crop", crop.toJson());
        }
        putIfSet(o, "tone_curve", toneCurve);
        return o;
    }

    /** Compact one-line ASCII JSON for the {@code X-Lumipose-Frame} header. */
    public String toHeaderValue() {
        return Json.asciiOnly(toJson().toString());
    }

    private static void putIfSet(JSONObject o, String key, Object v) {
        if (v != null) {
            Json.put(o, key, v);
        }
    }

    public static FrameMeta fromJson(String text) {
        return fromJson(Json.parseObject(text, "frame"));
    }

    public static FrameMeta fromJson(JSONObject o) {
        Json.checkSchema(o, SCHEMA);
        Builder b = builder(Json.requireInt(o, "width", "width"), Json.requireInt(o, "height", "height"));
        String format = Json.optString(o, "format", "format");
        if (format != null) {
            if (!Arrays.asList("Y8", "NV21", "I420", "PNG").contains(format)) {
                throw new ContractException("format", "must be Y8, NV21, I420 or PNG, got '" + format + "'");
            }
            b.format = format;
        }
        Long stride = Json.optLong(o, "row_stride", "row_stride");
        if (stride != null) {
            b.rowStride((int) ContractRanges.ROW_STRIDE.check("row_stride", stride.doubleValue()));
        }
        JSONObject cam = Json.requireObject(o, "camera", "camera");
        String profile = Json.optString(cam, "profile", "camera.profile");
        if (profile != null) {
            b.cameraProfile(profile);
        } else {
            double[] distortion = Json.optDoubles(cam, "distortion", "camera.distortion", -1);
            b.camera(new Intrinsics(Json.requireDouble(cam, "fx", "camera.fx"), Json.requireDouble(cam, "fy", "camera.fy"),
                    Json.requireDouble(cam, "cx", "camera.cx"), Json.requireDouble(cam, "cy", "camera.cy"),
                    distortion, Json.optDouble(cam, "pixel_size_m", "camera.pixel_size_m"),
                    Json.optDouble(cam, "focal_length_m", "camera.focal_length_m"),
                    Json.optString(cam, "device", "camera.device")));
        }
        b.cameraExtras = Json.extras(cam, KNOWN_CAMERA);
        b.exposureS(Json.optDouble(o, "exposure_s", "exposure_s"));
        b.iso(Json.optDouble(o, "iso", "iso"));
        b.rollingShutterSkewS(Json.optDouble(o, "rolling_shutter_skew_s", "rolling_shutter_skew_s"));
        b.timestampNs(Json.optLong(o, "timestamp_ns", "timestamp_ns"));
        b.headingDeg(Json.optDouble(o, "heading_deg", "heading_deg"));
        b.compassBearingDeg(Json.optDouble(o, "compass_bearing_deg", "compass_bearing_deg"));
        b.gravityCamera(Json.optDoubles(o, "gravity_camera", "gravity_camera", 3));
        b.angularVelocityCameraDps(Json.optDoubles(o, "angular_velocity_camera_dps", "angular_velocity_camera_dps", 3));
        b.frameKind(Json.optString(o, "frame_kind", "frame_kind"));
        JSONObject crop = Json.optObject(o, "crop", "crop");
        if (crop != null) {
            b.crop = Crop.fromJson(crop);
        }
        b.toneCurve(Json.optString(o, "tone_curve", "tone_curve"));
        b.extras = Json.extras(o, KNOWN);
        return b.build();
    }

    /** Builds a frame's JSON; width and height are required, the rest optional. */
    public static final class Builder {
        private String format = "Y8";
        private final int width;
        private final int height;
        private Integer rowStride;
        private Intrinsics camera;
        private String cameraProfile;
        private Double exposureS;
        private Double iso;
        private Double rollingShutterSkewS;
        private Long timestampNs;
        private Double headingDeg;
        private Double compassBearingDeg;
        private double[] gravityCamera;
        private double[] angularVelocityCameraDps;
        private String frameKind;
        private Crop crop;
        private String toneCurve;
        private JSONObject extras = new JSONObject();
        private JSONObject cameraExtras = new JSONObject();

        private Builder(int width, int height) {
            this.width = width;
            this.height = height;
        }

        public Builder rowStride(int v) {
            rowStride = v;
            return this;
        }

        public Builder camera(Intrinsics v) {
            camera = v;
            return this;
        }

        public Builder cameraProfile(String v) {
            cameraProfile = v;
            return this;
        }

        public Builder exposureS(Double v) {
            exposureS = v;
            return this;
        }

        public Builder iso(Double v) {
            iso = v;
            return this;
        }

        public Builder rollingShutterSkewS(Double v) {
            rollingShutterSkewS = v;
            return this;
        }

        public Builder timestampNs(Long v) {
            timestampNs = v;
            return this;
        }

        public Builder headingDeg(Double v) {
            headingDeg = v;
            return this;
        }

        /** The compass bearing of the image's +x laid level, deg clockwise from north; null for none. */
        public Builder compassBearingDeg(Double v) {
            compassBearingDeg = v;
            return this;
        }

        public Builder gravityCamera(double[] v) {
            gravityCamera = v == null ? null : v.clone();
            return this;
        }

        /** The gyroscope's rate over the readout, camera frame, deg/s; null for none. */
        public Builder angularVelocityCameraDps(double[] v) {
            angularVelocityCameraDps = v == null ? null : v.clone();
            return this;
        }

        public Builder frameKind(String v) {
            frameKind = v;
            return this;
        }

        /**
         * These pixels are the window {@code width x height} at ({@code x}, {@code y}) of a
         * {@code fullWidth x fullHeight} frame, which the intrinsics describe.
         */
        public Builder crop(int x, int y, int fullWidth, int fullHeight) {
            return crop(x, y, fullWidth, fullHeight, null);
        }

        /** The same, with the full frame's [background, plateau] grey levels ({@code crop.levels_dn}). */
        public Builder crop(int x, int y, int fullWidth, int fullHeight, double[] levelsDn) {
            crop = new Crop(x, y, fullWidth, fullHeight, levelsDn);
            return this;
        }

        /** "linear", "srgb" or "device": the tone curve the camera applied. */
        public Builder toneCurve(String v) {
            toneCurve = v;
            return this;
        }

        /** An extra top-level field (the contract allows and keeps them). */
        public Builder extra(String key, Object value) {
            if ("tone_curve".equals(key)) { // it was an extra before it became a field
                return toneCurve((String) value);
            }
            if (KNOWN.contains(key)) {
                throw new IllegalArgumentException("'" + key + "' is a contract field, set it with its own method");
            }
            Json.put(extras, key, value);
            return this;
        }

        public FrameMeta build() {
            return new FrameMeta(this);
        }
    }

    /** The contract's {@code crop} block: where a window's pixels lie in the full frame. */
    public static final class Crop {
        public final int x;
        public final int y;
        public final int fullWidth;
        public final int fullHeight;
        /** The full frame's [background, plateau] grey levels ({@code levels_dn}), or null. */
        private final double[] levelsDn;

        public Crop(int x, int y, int fullWidth, int fullHeight, double[] levelsDn) {
            this.x = (int) ContractRanges.CROP_OFFSET_PX.check("crop.x", x);
            this.y = (int) ContractRanges.CROP_OFFSET_PX.check("crop.y", y);
            this.fullWidth = (int) ContractRanges.SIDE_PX.check("crop.full_width", fullWidth);
            this.fullHeight = (int) ContractRanges.SIDE_PX.check("crop.full_height", fullHeight);
            if (levelsDn != null) {
                if (levelsDn.length != 2) {
                    throw new ContractException("crop.levels_dn", "must hold [background, plateau]");
                }
                ContractRanges.GREY_LEVEL_DN.checkEach("crop.levels_dn", levelsDn);
                if (levelsDn[0] > levelsDn[1]) {
                    throw new ContractException("crop.levels_dn", "background " + levelsDn[0] + " > plateau "
                            + levelsDn[1]);
                }
            }
            this.levelsDn = levelsDn == null ? null : levelsDn.clone();
        }

        public double[] levelsDn() {
            return levelsDn == null ? null : levelsDn.clone();
        }

        static Crop fromJson(JSONObject o) {
            return new Crop(Json.requireInt(o, "x", "crop.x"), Json.requireInt(o, "y", "crop.y"),
                    Json.requireInt(o, "full_width", "crop.full_width"),
                    Json.requireInt(o, "full_height", "crop.full_height"),
                    Json.optDoubles(o, "levels_dn", "crop.levels_dn", 2));
        }

        void checkHolds(int width, int height) {
            if ((long) x + width > fullWidth || (long) y + height > fullHeight) {
                throw new ContractException("crop", "window " + width + "x" + height + " at (" + x + ", " + y
                        + ") does not fit in the full frame " + fullWidth + "x" + fullHeight);
            }
        }

        JSONObject toJson() {
            JSONObject o = new JSONObject();
            Json.put(o, "x", x);
            Json.put(o, "y", y);
            Json.put(o, "full_width", fullWidth);
            Json.put(o, "full_height", fullHeight);
            if (levelsDn != null) {
                Json.put(o, "levels_dn", Json.array(levelsDn));
            }
            return o;
        }
    }
}
