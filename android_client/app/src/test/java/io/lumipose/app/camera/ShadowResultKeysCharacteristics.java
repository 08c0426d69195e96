package io.lumipose.app.camera;

import android.hardware.camera2.CameraCharacteristics;
import android.hardware.camera2.CaptureResult;

import java.util.ArrayList;
import java.util.Arrays;
import java.util.Collections;
import java.util.List;

import org.robolectric.annotation.Implementation;
import org.robolectric.annotation.Implements;
import org.robolectric.annotation.Resetter;

/**
 * Robolectric's characteristics have no list of result keys (the real one maps the HAL's tags
 * natively): this one answers {@code getAvailableCaptureResultKeys()} with the keys of a camera
 * that reports its timestamps, exposure and rolling-shutter skew, or what a test sets. For every
 * camera at once: CameraManager hands out copies of the characteristics it was given.
 */
@Implements(CameraCharacteristics.class)
public class ShadowResultKeysCharacteristics extends org.robolectric.shadows.ShadowCameraCharacteristics {
    private static final List<CaptureResult.Key<?>> DEFAULT = Collections.unmodifiableList(
            Arrays.<CaptureResult.Key<?>>asList(CaptureResult.SENSOR_TIMESTAMP, CaptureResult.SENSOR_EXPOSURE_TIME,
                    CaptureResult.SENSOR_ROLLING_SHUTTER_SKEW));
    private static volatile List<CaptureResult.Key<?>> resultKeys = DEFAULT;

    public static void setResultKeys(List<CaptureResult.Key<?>> keys) {
        resultKeys = Collections.unmodifiableList(new ArrayList<CaptureResult.Key<?>>(keys));
    }

    @Implementation
    protected List<CaptureResult.Key<?>> getAvailableCaptureResultKeys() {
        return resultKeys;
    }

    @Resetter
    public static void reset() {
        resultKeys = DEFAULT;
    }
}
