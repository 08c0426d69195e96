package io.lumipose.app;

import android.hardware.camera2.CaptureResult;
import android.hardware.camera2.TotalCaptureResult;

import io.lumipose.client.camera.Camera2Names;
import io.lumipose.client.camera.FrameResult;

/** Copies what one TotalCaptureResult says into the core's FrameResult (docs/android.md). No decisions here. */
final class FrameResultReader {
    private FrameResultReader() {
    }

    /** Null when the result has no SENSOR_TIMESTAMP (it cannot be matched to its image). */
    static FrameResult read(TotalCaptureResult r) {
        Long timestamp = r.get(CaptureResult.SENSOR_TIMESTAMP);
        if (timestamp == null) {
            return null;
        }
        Object tag = r.getRequest().getTag();
        FrameResult.Builder b = FrameResult.builder(timestamp)
                .request(tag instanceof String ? (String) tag : null)
                .exposureNs(r.get(CaptureResult.SENSOR_EXPOSURE_TIME))
                .sensitivityIso(r.get(CaptureResult.SENSOR_SENSITIVITY))
                .frameDurationNs(r.get(CaptureResult.SENSOR_FRAME_DURATION))
                .rollingShutterSkewNs(r.get(CaptureResult.SENSOR_ROLLING_SHUTTER_SKEW))
                .focalLengthMm(asDouble(r.get(CaptureResult.LENS_FOCAL_LENGTH)))
                .lensIntrinsicCalibration(CameraFactsReader.doubles(r.get(CaptureResult.LENS_INTRINSIC_CALIBRATION)))
                .lensDistortion(CameraFactsReader.doubles(r.get(CaptureResult.LENS_DISTORTION)))
                .lensRadialDistortion(CameraFactsReader.doubles(radialDistortion(r)))
                .cropRegion(CameraFactsReader.rect(r.get(CaptureResult.SCALER_CROP_REGION)))
                .focusDistanceDiopters(asDouble(r.get(CaptureResult.LENS_FOCUS_DISTANCE)));
        Integer ois = r.get(CaptureResult.LENS_OPTICAL_STABILIZATION_MODE);
        b.oisMode(ois == null ? null : Camera2Names.oisMode(ois));
        Integer tonemap = r.get(CaptureResult.TONEMAP_MODE);
        b.tonemapMode(tonemap == null ? null : Camera2Names.tonemapMode(tonemap));
        Integer preset = r.get(CaptureResult.TONEMAP_PRESET_CURVE);
        b.tonemapPresetCurve(preset == null ? null : Camera2Names.tonemapPresetCurve(preset));
        Integer correction = r.get(CaptureResult.DISTORTION_CORRECTION_MODE);
        b.distortionCorrectionMode(correction == null ? null : Camera2Names.distortionCorrectionMode(correction));
        if (Camera2Keys.available()) {
            Integer rotate = r.get(Camera2Keys.RESULT_ROTATE_AND_CROP);
            b.rotateAndCrop(rotate == null ? null : Camera2Names.rotateAndCrop(rotate));
            b.zoomRatio(asDouble(r.get(Camera2Keys.RESULT_ZOOM_RATIO)));
        }
        return b.build();
    }

    @SuppressWarnings("deprecation")
    private static float[] radialDistortion(TotalCaptureResult r) {
        return r.get(CaptureResult.LENS_RADIAL_DISTORTION);
    }

    private static Double asDouble(Float v) {
        return v == null ? null : v.doubleValue();
    }
}
