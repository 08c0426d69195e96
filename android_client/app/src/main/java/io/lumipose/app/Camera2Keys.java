package io.lumipose.app;

import android.hardware.camera2.CameraCharacteristics;
import android.hardware.camera2.CaptureRequest;
import android.hardware.camera2.CaptureResult;
import android.os.Build;

/**
 * The Android 11 (API 30) keys, made by name: the app compiles against Android 10's framework
 * classes, and the public Key(String, Class) constructors give the same keys on an API 30 phone.
 * Use them only where {@link #available()}; below API 30 they are null.
 *
 * <p>Those constructors are public only from API 29 (hidden on 28, the minSdk), and this class is
 * initialized on every phone (available() is called everywhere): so they are called in {@link Api30}
 * alone, a class this one touches only after finding API 30.
 */
final class Camera2Keys {
    static final CameraCharacteristics.Key<int[]> ROTATE_AND_CROP_MODES =
            available() ? Api30.ROTATE_AND_CROP_MODES : null;
    /** A Range<Float> in Camera2; read as its two floats. */
    static final CameraCharacteristics.Key<float[]> ZOOM_RATIO_RANGE = available() ? Api30.ZOOM_RATIO_RANGE : null;
    static final CaptureRequest.Key<Integer> REQUEST_ROTATE_AND_CROP =
            available() ? Api30.REQUEST_ROTATE_AND_CROP : null;
    static final CaptureRequest.Key<Float> REQUEST_ZOOM_RATIO = available() ? Api30.REQUEST_ZOOM_RATIO : null;
    static final CaptureResult.Key<Integer> RESULT_ROTATE_AND_CROP = available() ? Api30.RESULT_ROTATE_AND_CROP : null;
    static final CaptureResult.Key<Float> RESULT_ZOOM_RATIO = available() ? Api30.RESULT_ZOOM_RATIO : null;
    /** SCALER_ROTATE_AND_CROP_NONE. */
    static final int ROTATE_AND_CROP_NONE = 0;

    private Camera2Keys() {
    }

    static boolean available() {
        return Build.VERSION.SDK_INT >= 30;
    }

    /** Initialized on the first read of a field, which only the checks above make, on API 30 and later. */
    @OnlyOnApi(30)
    private static final class Api30 {
        static final CameraCharacteristics.Key<int[]> ROTATE_AND_CROP_MODES =
                new CameraCharacteristics.Key<int[]>("android.scaler.availableRotateAndCropModes", int[].class);
        static final CameraCharacteristics.Key<float[]> ZOOM_RATIO_RANGE =
                new CameraCharacteristics.Key<float[]>("android.control.zoomRatioRange", float[].class);
        static final CaptureRequest.Key<Integer> REQUEST_ROTATE_AND_CROP =
                new CaptureRequest.Key<Integer>("android.scaler.rotateAndCrop", int.class);
        static final CaptureRequest.Key<Float> REQUEST_ZOOM_RATIO =
                new CaptureRequest.Key<Float>("android.control.zoomRatio", float.class);
        static final CaptureResult.Key<Integer> RESULT_ROTATE_AND_CROP =
                new CaptureResult.Key<Integer>("android.scaler.rotateAndCrop", int.class);
        static final CaptureResult.Key<Float> RESULT_ZOOM_RATIO =
                new CaptureResult.Key<Float>("android.control.zoomRatio", float.class);
    }
}
