package io.lumipose.client.camera;

import org.json.JSONObject;

import io.lumipose.client.contract.ContractRanges;
import io.lumipose.client.json.ContractException;
import io.lumipose.client.json.Json;
import io.lumipose.client.sensor.LensFacing;

/**
 * The contract's {@code DeviceProfile}: a phone camera at its output size {@code width x height},
 * as its maker describes it (datasheet: focal length / pixel pitch, principal point at the centre)
 * or as a calibration measured it ({@code intrinsics}, {@link MeasuredPinhole}). Unknown fields are
 * refused, as the contract refuses them.
 */
public final class DeviceProfile {
    public static final String FRONT = "front";
    public static final String REAR = "rear";

    public final String id;
    public final String name;
    public final String sensor;
    /** "front" or "rear". */
    public final String facing;
    public final double pixelSizeM;
    public final double focalLengthM;
    public final int width;
    public final int height;
    private final double[] distortion;
    public final double gravitySigmaDeg;
    /** The calibrated pinhole at width x height; null for a datasheet profile. */
    public final MeasuredPinhole intrinsics;

    /** A calibration's pinhole at the profile's size. */
    public static final class MeasuredPinhole {
        public final double fx;
        public final double fy;
        public final double cx;
        public final double cy;
        /** Reprojection RMS of the calibration, px; null when not given. */
        public final Double rmsPx;
        /** Board photos used; null when not given. */
        public final Integer views;

        public MeasuredPinhole(double fx, double fy, double cx, double cy, Double rmsPx, Integer views) {
            this.fx = ContractRanges.FOCAL_PX.check("intrinsics.fx", fx);
            this.fy = ContractRanges.FOCAL_PX.check("intrinsics.fy", fy);
            this.cx = ContractRanges.PRINCIPAL_PX.check("intrinsics.cx", cx);
            this.cy = ContractRanges.PRINCIPAL_PX.check("intrinsics.cy", cy);
            if (rmsPx != null && !(rmsPx >= 0)) {
                throw new ContractException("intrinsics.rms_px", "must be >= 0, got " + rmsPx);
            }
            if (views != null && views < 1) {
                throw new ContractException("intrinsics.views", "must be >= 1, got " + views);
            }
            this.rmsPx = rmsPx;
            this.views = views;
        }
    }

    public DeviceProfile(String id, String name, String sensor, String facing, double pixelSizeM, double focalLengthM,
                         int width, int height, double[] distortion, double gravitySigmaDeg,
                         MeasuredPinhole intrinsics) {
        ContractRanges.checkName("id", id);
        if (name == null || sensor == null) {
            throw new ContractException(name == null ? "name" : "sensor", "missing");
        }
        if (!FRONT.equals(facing) && !REAR.equals(facing)) {
            throw new ContractException("facing", "must be 'front' or 'rear', got '" + facing + "'");
        }
        this.id = id;
        this.name = name;
        this.sensor = sensor;
        this.facing = facing;
        this.pixelSizeM = ContractRanges.PIXEL_SIZE_M.check("pixel_size_m", pixelSizeM);
        this.focalLengthM = ContractRanges.FOCAL_LENGTH_M.check("focal_length_m", focalLengthM);
        this.width = (int) ContractRanges.SIDE_PX.check("width", width);
        this.height = (int) ContractRanges.SIDE_PX.check("height", height);
        double[] d = distortion == null ? new double[0] : distortion.clone();
        if (d.length != 0 && d.length != 4 && d.length != 5 && d.length != 8) {
            throw new ContractException("distortion", "must hold 0, 4, 5 or 8 OpenCV coefficients, got " + d.length);
        }
        this.distortion = ContractRanges.DISTORTION.checkEach("distortion", d);
        if (!(gravitySigmaDeg >= 0 && gravitySigmaDeg <= 90)) {
            throw new ContractException("gravity_sigma_deg", "must be within [0, 90], got " + gravitySigmaDeg);
        }
        this.gravitySigmaDeg = gravitySigmaDeg;
        this.intrinsics = intrinsics;
    }

    /**
     * The phone's own datasheet profile for a calibration request, from one frame's camera as the
     * app describes it (its pixel pitch and focal length at the output size {@code width x height}).
     *
     * @param id   a profile id; characters the service refuses become '-' ({@link #safeId})
     * @throws IllegalArgumentException naming what is missing (a camera without a focal length)
     */
    public static DeviceProfile ofPhone(String id, String name, LensFacing facing, Intrinsics camera, int width,
                                        int height) {
        if (camera.focalLengthM == null || camera.pixelSizeM == null) {
            throw new IllegalArgumentException("the camera reports no focal length: its profile cannot be made");
        }
        return new DeviceProfile(safeId(id), name, "unknown", facing == LensFacing.FRONT ? FRONT : REAR,
                camera.pixelSizeM, camera.focalLengthM, width, height, camera.distortion(), 0.1, null);
    }

    /** {@code raw} as a profile id: other characters than [A-Za-z0-9_.-] become '-', at most 64. */
    public static String safeId(String raw) {
        String s = raw == null ? "" : raw.trim().replaceAll("[^A-Za-z0-9_.-]", "-");
        while (s.startsWith("-") || s.startsWith(".") || s.startsWith("_")) {
            s = s.substring(1);
        }
        if (s.isEmpty()) {
            s = "phone";
        }
        return s.length() > 64 ? s.substring(0, 64) : s;
    }

    public double[] distortion() {
        return distortion.clone();
    }

    /**
     * The profile's pinhole for a frame of {@code frameWidth x frameHeight}: the measured intrinsics
     * (else the datasheet's) of the profile's image scaled by s = max(w / W, h / H) and
     * centre-cropped, a pixel centre u landing at (u + 1/2) s - 1/2 less the crop's offset; the same
     * rule as the server's {@code intrinsics_from_profile} (server/camera.py), which the tests compare.
     */
    public Intrinsics forFrame(int frameWidth, int frameHeight) {
        double s = Math.max((double) frameWidth / width, (double) frameHeight / height);
        double fx;
        double fy;
        double cx;
        double cy;
        if (intrinsics == null) {
            fx = focalLengthM / pixelSizeM * s;
            fy = fx;
            cx = (frameWidth - 1) / 2.0;
            cy = (frameHeight - 1) / 2.0;
        } else {
            fx = intrinsics.fx * s;
            fy = intrinsics.fy * s;
            cx = (intrinsics.cx + 0.5) * s - 0.5 - (width * s - frameWidth) / 2;
            cy = (intrinsics.cy + 0.5) * s - 0.5 - (height * s - frameHeight) / 2;
        }
        return new Intrinsics(fx, fy, cx, cy, distortion, pixelSizeM / s, focalLengthM, name);
    }

    public JSONObject toJson() {
        JSONObject o = new JSONObject();
        Json.put(o, "id", id);
        Json.put(o, "name", name);
        Json.put(o, "sensor", sensor);
        Json.put(o, "facing", facing);
        Json.put(o, "pixel_size_m", pixelSizeM);
        Json.put(o, "focal_length_m", focalLengthM);
        Json.put(o, "width", width);
        Json.put(o, "height", height);
        Json.put(o, "distortion", Json.array(distortion));
        Json.put(o, "gravity_sigma_deg", gravitySigmaDeg);
        if (intrinsics != null) {
            JSONObject k = new JSONObject();
            Json.put(k, "fx", intrinsics.fx);
            Json.put(k, "fy", intrinsics.fy);
            Json.put(k, "cx", intrinsics.cx);
            Json.put(k, "cy", intrinsics.cy);
            if (intrinsics.rmsPx != null) {
                Json.put(k, "rms_px", intrinsics.rmsPx);
            }
            if (intrinsics.views != null) {
                Json.put(k, "views", intrinsics.views);
            }
            Json.put(o, "intrinsics", k);
        }
        return o;
    }

    public static DeviceProfile fromJson(String text) {
        return fromJson(Json.parseObject(text, "profile"), "");
    }

    /** @param path where the profile sits in its document ("profile." in a report), for the errors */
    public static DeviceProfile fromJson(JSONObject o, String path) {
        JSONObject unknown = Json.extras(o, java.util.Collections.<String>emptySet());
        for (String known : new String[] {"id", "name", "sensor", "facing", "pixel_size_m", "focal_length_m",
            "width", "height", "distortion", "gravity_sigma_deg", "intrinsics"}) {
            unknown.remove(known);
        }
        if (unknown.length() > 0) {
            throw new ContractException(path + unknown.keys().next(), "not a field of a device profile");
        }
        try {
            JSONObject k = Json.optObject(o, "intrinsics", path + "intrinsics");
            MeasuredPinhole pinhole = null;
            if (k != null) {
                Long views = Json.optLong(k, "views", path + "intrinsics.views");
                pinhole = new MeasuredPinhole(Json.requireDouble(k, "fx", path + "intrinsics.fx"),
                        Json.requireDouble(k, "fy", path + "intrinsics.fy"),
                        Json.requireDouble(k, "cx", path + "intrinsics.cx"),
                        Json.requireDouble(k, "cy", path + "intrinsics.cy"),
                        Json.optDouble(k, "rms_px", path + "intrinsics.rms_px"),
                        views == null ? null : Integer.valueOf(views.intValue()));
            }
            Double sigma = Json.optDouble(o, "gravity_sigma_deg", path + "gravity_sigma_deg");
            return new DeviceProfile(Json.optString(o, "id", path + "id"), Json.optString(o, "name", path + "name"),
                    Json.optString(o, "sensor", path + "sensor"), Json.optString(o, "facing", path + "facing"),
                    Json.requireDouble(o, "pixel_size_m", path + "pixel_size_m"),
                    Json.requireDouble(o, "focal_length_m", path + "focal_length_m"),
                    Json.requireInt(o, "width", path + "width"), Json.requireInt(o, "height", path + "height"),
                    Json.optDoubles(o, "distortion", path + "distortion", -1), sigma == null ? 0.1 : sigma, pinhole);
        } catch (ContractException e) {
            if (path.isEmpty() || e.field.startsWith(path)) {
                throw e;
            }
            throw e.within(path);
        }
    }
}
