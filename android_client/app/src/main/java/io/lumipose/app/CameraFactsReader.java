package io.lumipose.app;

import android.graphics.ImageFormat;
import android.graphics.Rect;
import android.hardware.camera2.CameraCharacteristics;
import android.hardware.camera2.params.StreamConfigurationMap;
import android.util.Range;
import android.util.Size;
import android.util.SizeF;

import io.lumipose.client.camera.ArrayRect;
import io.lumipose.client.camera.Camera2Names;
import io.lumipose.client.camera.CameraFacts;
import io.lumipose.client.camera.PixelSize;

/** Copies what the core needs out of CameraCharacteristics (docs/android.md's CameraFacts). No decisions here. */
final class CameraFactsReader {
    private CameraFactsReader() {
    }

    /** @throws IllegalArgumentException naming the key when a required one is missing */
    static CameraFacts read(String cameraId, CameraCharacteristics cc) {
        CameraFacts.Builder b = CameraFacts.builder().cameraId(cameraId);
        Integer facing = cc.get(CameraCharacteristics.LENS_FACING);
        b.lensFacing(facing == null ? null : Camera2Names.lensFacing(facing));
        b.sensorOrientationDeg(orZero(cc.get(CameraCharacteristics.SENSOR_ORIENTATION)));
        b.capabilities(Camera2Names.names(cc.get(CameraCharacteristics.REQUEST_AVAILABLE_CAPABILITIES),
                Camera2Names.CAPABILITY));
        Integer sync = cc.get(CameraCharacteristics.SYNC_MAX_LATENCY);
        b.syncMaxLatency(sync == null ? CameraFacts.SYNC_UNKNOWN : Camera2Names.syncMaxLatency(sync));
        Integer source = cc.get(CameraCharacteristics.SENSOR_INFO_TIMESTAMP_SOURCE);
        b.timestampSource(source == null ? null : Camera2Names.timestampSource(source));
        b.activeArray(rect(cc.get(CameraCharacteristics.SENSOR_INFO_ACTIVE_ARRAY_SIZE)));
        b.preCorrectionActiveArray(rect(cc.get(CameraCharacteristics.SENSOR_INFO_PRE_CORRECTION_ACTIVE_ARRAY_SIZE)));
        Size pixels = cc.get(CameraCharacteristics.SENSOR_INFO_PIXEL_ARRAY_SIZE);
        b.pixelArray(pixels == null ? null : new PixelSize(pixels.getWidth(), pixels.getHeight()));
        SizeF physical = cc.get(CameraCharacteristics.SENSOR_INFO_PHYSICAL_SIZE);
        if (physical != null) {
            b.physicalSizeMm(physical.getWidth(), physical.getHeight());
        }
        b.availableFocalLengthsMm(doubles(cc.get(CameraCharacteristics.LENS_INFO_AVAILABLE_FOCAL_LENGTHS)));
        b.lensIntrinsicCalibration(doubles(cc.get(CameraCharacteristics.LENS_INTRINSIC_CALIBRATION)));
        b.lensDistortion(doubles(cc.get(CameraCharacteristics.LENS_DISTORTION)));
        b.lensRadialDistortion(doubles(radialDistortion(cc)));
        Float minimumFocus = cc.get(CameraCharacteristics.LENS_INFO_MINIMUM_FOCUS_DISTANCE);
        b.minimumFocusDistanceDiopters(minimumFocus == null ? null : minimumFocus.doubleValue());
        Integer focusCalibration = cc.get(CameraCharacteristics.LENS_INFO_FOCUS_DISTANCE_CALIBRATION);
        b.focusDistanceCalibration(focusCalibration == null ? null
                : Camera2Names.focusDistanceCalibration(focusCalibration));
        b.oisModes(Camera2Names.names(cc.get(CameraCharacteristics.LENS_INFO_AVAILABLE_OPTICAL_STABILIZATION),
                Camera2Names.OIS_MODE));
        b.tonemapModes(Camera2Names.names(cc.get(CameraCharacteristics.TONEMAP_AVAILABLE_TONE_MAP_MODES),
                Camera2Names.TONEMAP_MODE));
        b.tonemapMaxCurvePoints(cc.get(CameraCharacteristics.TONEMAP_MAX_CURVE_POINTS));
        b.edgeModes(Camera2Names.names(cc.get(CameraCharacteristics.EDGE_AVAILABLE_EDGE_MODES),
                Camera2Names.EDGE_MODE));
        b.noiseReductionModes(Camera2Names.names(
                cc.get(CameraCharacteristics.NOISE_REDUCTION_AVAILABLE_NOISE_REDUCTION_MODES),
                Camera2Names.NOISE_REDUCTION_MODE));
        b.distortionCorrectionModes(Camera2Names.names(
                cc.get(CameraCharacteristics.DISTORTION_CORRECTION_AVAILABLE_MODES),
                Camera2Names.DISTORTION_CORRECTION_MODE));
        if (Camera2Keys.available()) {
            b.rotateAndCropModes(Camera2Names.names(cc.get(Camera2Keys.ROTATE_AND_CROP_MODES),
                    Camera2Names.ROTATE_AND_CROP_MODE));
            b.zoomRatioRange(doubles(cc.get(Camera2Keys.ZOOM_RATIO_RANGE)));
        }
        Range<Long> exposure = cc.get(CameraCharacteristics.SENSOR_INFO_EXPOSURE_TIME_RANGE);
        if (exposure != null) {
            b.exposureTimeRangeNs(exposure.getLower(), exposure.getUpper());
        }
        Range<Integer> iso = cc.get(CameraCharacteristics.SENSOR_INFO_SENSITIVITY_RANGE);
        if (iso != null) {
            b.sensitivityRange(iso.getLower(), iso.getUpper());
        }
        b.maxFrameDurationNs(cc.get(CameraCharacteristics.SENSOR_INFO_MAX_FRAME_DURATION));
        StreamConfigurationMap streams = cc.get(CameraCharacteristics.SCALER_STREAM_CONFIGURATION_MAP);
        Size[] sizes = streams == null ? null : streams.getOutputSizes(ImageFormat.YUV_420_888);
        if (sizes != null) {
            for (Size s : sizes) {
                b.addYuvOutput(new PixelSize(s.getWidth(), s.getHeight()),
                        Math.max(0, streams.getOutputMinFrameDuration(ImageFormat.YUV_420_888, s)));
            }
        }
        return b.build();
    }

    /** Does the result list SENSOR_ROLLING_SHUTTER_SKEW? Without it an ID frame's rows have no times. */
    static boolean reportsRollingShutterSkew(CameraCharacteristics cc) {
        return cc.getAvailableCaptureResultKeys().contains(
                android.hardware.camera2.CaptureResult.SENSOR_ROLLING_SHUTTER_SKEW);
    }

    @SuppressWarnings("deprecation")
    private static float[] radialDistortion(CameraCharacteristics cc) {
        return cc.get(CameraCharacteristics.LENS_RADIAL_DISTORTION);
    }

    static ArrayRect rect(Rect r) {
        return r == null || r.width() <= 0 || r.height() <= 0 ? null : new ArrayRect(r.left, r.top, r.width(), r.height());
    }

    static double[] doubles(float[] v) {
        if (v == null) {
            return null;
        }
        double[] out = new double[v.length];
        for (int i = 0; i < v.length; i++) {
            out[i] = v[i];
        }
        return out;
    }

    private static int orZero(Integer v) {
        return v == null ? 0 : v;
    }
}
