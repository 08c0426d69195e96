package io.lumipose.app;

import android.Manifest;
import android.content.Context;
import android.content.pm.PackageManager;
import android.graphics.ImageFormat;
import android.graphics.Rect;
import android.hardware.camera2.CameraAccessException;
import android.hardware.camera2.CameraCaptureSession;
import android.hardware.camera2.CameraCharacteristics;
import android.hardware.camera2.CameraDevice;
import android.hardware.camera2.CameraManager;
import android.hardware.camera2.CameraMetadata;
import android.hardware.camera2.CaptureRequest;
import android.hardware.camera2.TotalCaptureResult;
import android.hardware.camera2.params.StreamConfigurationMap;
import android.media.Image;
import android.media.ImageReader;
import android.os.Handler;
import android.os.HandlerThread;
import android.util.Range;
import android.util.Size;
import android.util.SizeF;

import java.util.ArrayList;
import java.util.Collections;
import java.util.LinkedHashMap;
import java.util.List;
import java.util.Map;

import io.lumipose.client.camera.ArrayRect;
import io.lumipose.client.camera.Intrinsics;
import io.lumipose.client.camera.IntrinsicsCalculator;
import io.lumipose.client.camera.LensDistortion;
import io.lumipose.client.camera.OutputSizeChooser;
import io.lumipose.client.camera.PixelSize;
import io.lumipose.client.capture.CameraRanges;
import io.lumipose.client.capture.CaptureSettings;
import io.lumipose.client.capture.CaptureSettingsChooser;
import io.lumipose.client.capture.IdCapturePlan;
import io.lumipose.client.capture.UnsupportedCameraException;
import io.lumipose.client.frame.CaptureValues;
import io.lumipose.client.frame.FrameAssembler;
import io.lumipose.client.frame.FrameMeta;
import io.lumipose.client.frame.LumaPlane;
import io.lumipose.client.sensor.GravitySource;
import io.lumipose.client.sensor.LensFacing;

/**
 * The only code that holds the Context and the camera. Runs Camera2 on its own HandlerThread with
 * auto-exposure and autofocus off, at the exposure, ISO and frame duration the core chose, and
 * hands out packed Y planes with their frame JSON. A camera without MANUAL_SENSOR is refused with
 * a reason instead of being used with automatic exposure. When beacon IDs are wanted it repeats a
 * burst of one pose frame and two short-exposure ID frames (the VLC capture protocol).
 */
final class Camera2Controller {
    /** Told what happens; every call comes on the camera thread. */
    interface Listener {
        void onStarted(String summary);

        void onUnsupported(String reason);

        void onFrame(byte[] luma, FrameMeta meta);

        void onError(String message);
    }

    /** Asked before each frame is copied: the Y copy is skipped while nobody wants a frame. */
    interface FrameGate {
        boolean wantFrame();
    }

    private static final int MAX_CAPTURE_VALUES = 8;
    private static final String ID_TAG = "id";
    private static final int ID_FRAMES_PER_POSE = IdCapturePlan.BURST_FRAMES;

    private final Context context;
    private final String requestedCameraId;
    private final long targetExposureNs;
    /** Zero: pose frames only. */
    private final long idExposureNs;
    private final float focusDistanceM;
    /** Compass bearing of the map's +X axis, deg; null: no heading is sent. */
    private final Double mapXBearingDeg;
    private final long maxPixels;
    private final GravitySource gravity;
    private final FrameGate gate;
    private final Listener listener;
    // Capture results by SENSOR_TIMESTAMP: the image and its result arrive separately (camera thread only).
    private final Map<Long, CaptureValues> captureValues = new LinkedHashMap<Long, CaptureValues>();

    private HandlerThread thread;
    private Handler handler;
    private CameraDevice camera;
    private CameraCaptureSession session;
    private ImageReader reader;
    private FrameAssembler assembler;
    private CaptureSettings settings;
    private CaptureSettings idSettings;
    // A copied frame whose capture result has not arrived yet (both come on the camera thread).
    private byte[] pendingLuma;
    private long pendingTimestampNs;
    private float[] pendingGravity;
    private float[] pendingRotation;

    Camera2Controller(Context context, String cameraId, long targetExposureNs, long idExposureNs,
                      float focusDistanceM, Double mapXBearingDeg, long maxPixels, GravitySource gravity,
                      FrameGate gate, Listener listener) {
        this.context = context.getApplicationContext();
        this.requestedCameraId = cameraId;
        this.targetExposureNs = targetExposureNs;
        this.idExposureNs = idExposureNs;
        this.focusDistanceM = focusDistanceM;
        this.mapXBearingDeg = mapXBearingDeg;
        this.maxPixels = maxPixels;
        this.gravity = gravity;
        this.gate = gate;
        this.listener = listener;
    }

    /** One line per camera for the settings screen: id, facing, whether it can be used. */
    static List<String[]> describeCameras(Context context) {
        List<String[]> out = new ArrayList<String[]>();
        CameraManager manager = (CameraManager) context.getSystemService(Context.CAMERA_SERVICE);
        try {
            for (String id : manager.getCameraIdList()) {
                CameraCharacteristics cc = manager.getCameraCharacteristics(id);
                Integer facing = cc.get(CameraCharacteristics.LENS_FACING);
                String side = facing == null ? "?" : facing == CameraMetadata.LENS_FACING_FRONT ? "front"
                        : facing == CameraMetadata.LENS_FACING_BACK ? "back" : "external";
                out.add(new String[] {id, side + (hasManualSensor(cc) ? "" : ", no manual exposure")});
            }
        } catch (CameraAccessException e) {
            out.add(new String[] {"", "cameras unavailable: " + e.getMessage()});
        }
        return out;
    }

    private static boolean hasManualSensor(CameraCharacteristics cc) {
        int[] caps = cc.get(CameraCharacteristics.REQUEST_AVAILABLE_CAPABILITIES);
        if (caps != null) {
            for (int c : caps) {
                if (c == CameraMetadata.REQUEST_AVAILABLE_CAPABILITIES_MANUAL_SENSOR) {
                    return true;
                }
            }
        }
        return false;
    }

    private static boolean contains(int[] values, int wanted) {
        if (values != null) {
            for (int v : values) {
                if (v == wanted) {
                    return true;
                }
            }
        }
        return false;
    }

    void start() {
        thread = new HandlerThread("lumipose-camera");
        thread.start();
        handler = new Handler(thread.getLooper());
        handler.post(new Runnable() {
            @Override
            public void run() {
                open();
            }
        });
    }

    void stop() {
        if (handler == null) {
            return;
        }
        handler.post(new Runnable() {
            @Override
            public void run() {
                closeCamera();
            }
        });
        thread.quitSafely();
        handler = null;
    }

    private void closeCamera() {
        if (session != null) {
            session.close();
            session = null;
        }
        if (camera != null) {
            camera.close();
            camera = null;
        }
        if (reader != null) {
            reader.close();
            reader = null;
        }
    }

    private String chooseCameraId(CameraManager manager) throws CameraAccessException {
        if (requestedCameraId != null && !requestedCameraId.isEmpty()) {
            return requestedCameraId;
        }
        for (String id : manager.getCameraIdList()) {
            CameraCharacteristics cc = manager.getCameraCharacteristics(id);
            Integer facing = cc.get(CameraCharacteristics.LENS_FACING);
            if (facing != null && facing == CameraMetadata.LENS_FACING_BACK && hasManualSensor(cc)) {
                return id;
            }
        }
        String[] all = manager.getCameraIdList();
        return all.length == 0 ? null : all[0];
    }

    private void open() {
        if (context.checkSelfPermission(Manifest.permission.CAMERA) != PackageManager.PERMISSION_GRANTED) {
            listener.onUnsupported("Camera permission not granted.");
            return;
        }
        final CameraManager manager = (CameraManager) context.getSystemService(Context.CAMERA_SERVICE);
        try {
            String id = chooseCameraId(manager);
            if (id == null) {
                listener.onUnsupported("This phone has no camera.");
                return;
            }
            final CameraCharacteristics cc = manager.getCameraCharacteristics(id);
            StreamConfigurationMap streams = cc.get(CameraCharacteristics.SCALER_STREAM_CONFIGURATION_MAP);
            Rect active = cc.get(CameraCharacteristics.SENSOR_INFO_ACTIVE_ARRAY_SIZE);
            if (streams == null || active == null) {
                listener.onUnsupported("Camera " + id + " reports no stream configuration or active array.");
                return;
            }
            List<PixelSize> offered = new ArrayList<PixelSize>();
            Size[] sizes = streams.getOutputSizes(ImageFormat.YUV_420_888);
            if (sizes != null) {
                for (Size s : sizes) {
                    offered.add(new PixelSize(s.getWidth(), s.getHeight()));
                }
            }
            ArrayRect activeRect = new ArrayRect(active.left, active.top, active.width(), active.height());
            final PixelSize out = OutputSizeChooser.choose(offered, activeRect, maxPixels);
            long minFrameNs = streams.getOutputMinFrameDuration(ImageFormat.YUV_420_888,
                    new Size(out.width, out.height));
            Range<Long> exposure = cc.get(CameraCharacteristics.SENSOR_INFO_EXPOSURE_TIME_RANGE);
            Range<Integer> iso = cc.get(CameraCharacteristics.SENSOR_INFO_SENSITIVITY_RANGE);
            CameraRanges ranges = new CameraRanges(hasManualSensor(cc),
                    exposure == null ? null : exposure.getLower(), exposure == null ? null : exposure.getUpper(),
                    iso == null ? null : iso.getLower(), iso == null ? null : iso.getUpper(),
                    cc.get(CameraCharacteristics.SENSOR_INFO_MAX_FRAME_DURATION), minFrameNs);
            settings = CaptureSettingsChooser.choose(ranges, targetExposureNs);
            idSettings = idExposureNs > 0 ? IdCapturePlan.choose(ranges, idExposureNs, settings,
                    IdCapturePlan.DEFAULT_BRIGHTNESS_FRACTION) : null;

            final boolean correctionOff = contains(cc.get(CameraCharacteristics.DISTORTION_CORRECTION_AVAILABLE_MODES),
                    CameraMetadata.DISTORTION_CORRECTION_MODE_OFF);
            Intrinsics k = intrinsics(cc, activeRect, out, correctionOff);
            Integer orientation = cc.get(CameraCharacteristics.SENSOR_ORIENTATION);
            Integer facing = cc.get(CameraCharacteristics.LENS_FACING);
            LensFacing lensFacing = facing == null ? null : facing == CameraMetadata.LENS_FACING_FRONT
                    ? LensFacing.FRONT : facing == CameraMetadata.LENS_FACING_BACK ? LensFacing.BACK : null;
            assembler = new FrameAssembler(out.width, out.height, k, orientation == null ? 0 : orientation,
                    lensFacing, mapXBearingDeg);
            final Float focus = CaptureSettingsChooser.focusDiopters(focusDistanceM,
                    cc.get(CameraCharacteristics.LENS_INFO_MINIMUM_FOCUS_DISTANCE));

            reader = ImageReader.newInstance(out.width, out.height, ImageFormat.YUV_420_888, 2);
            reader.setOnImageAvailableListener(new ImageReader.OnImageAvailableListener() {
                @Override
                public void onImageAvailable(ImageReader r) {
                    deliver(r);
                }
            }, handler);
            final String summary = "camera " + id + ", " + out + ", exposure " + settings.exposureNs / 1000 + " us, ISO "
                    + settings.sensitivityIso + ", fx " + Math.round(k.fx) + " px"
                    + (settings.notes.isEmpty() ? "" : "; " + settings.notes)
                    + (idSettings == null ? "" : "; ID frames " + idSettings.exposureNs / 1000 + " us at ISO "
                    + idSettings.sensitivityIso + (idSettings.notes.isEmpty() ? "" : " " + idSettings.notes));
            manager.openCamera(id, new CameraDevice.StateCallback() {
                @Override
                public void onOpened(CameraDevice device) {
                    camera = device;
                    startSession(cc, focus, correctionOff, summary);
                }

                @Override
                public void onDisconnected(CameraDevice device) {
                    device.close();
                    camera = null;
                    listener.onError("Camera disconnected.");
                }

                @Override
                public void onError(CameraDevice device, int error) {
                    device.close();
                    camera = null;
                    listener.onError("Camera error " + error + ".");
                }
            }, handler);
        } catch (UnsupportedCameraException e) {
            listener.onUnsupported(e.getMessage());
        } catch (CameraAccessException e) {
            listener.onError("Camera access failed: " + e.getMessage());
        } catch (IllegalArgumentException e) {
            listener.onUnsupported(e.getMessage());
        } catch (SecurityException e) {
            listener.onUnsupported("Camera permission refused: " + e.getMessage());
        }
    }

    /**
     * With correction OFF the stream covers the pre-correction array and keeps the lens distortion,
     * which is sent; a device without correction modes does no correction, so its stream is the active
     * array, still distorted.
     */
    private static Intrinsics intrinsics(CameraCharacteristics cc, ArrayRect active, PixelSize out,
                                         boolean correctionOff) {
        Rect pre = cc.get(CameraCharacteristics.SENSOR_INFO_PRE_CORRECTION_ACTIVE_ARRAY_SIZE);
        ArrayRect preRect = pre == null ? active : new ArrayRect(pre.left, pre.top, pre.width(), pre.height());
        ArrayRect source = correctionOff ? preRect : active;
        double[] distortion = LensDistortion.toOpenCv(cc.get(CameraCharacteristics.LENS_DISTORTION));
        String device = android.os.Build.MANUFACTURER + " " + android.os.Build.MODEL;
        float[] calibration = cc.get(CameraCharacteristics.LENS_INTRINSIC_CALIBRATION);
        if (IntrinsicsCalculator.isUsable(calibration)) {
            return IntrinsicsCalculator.fromLensCalibration(calibration, preRect, source, out, distortion, device);
        }
        float[] focal = cc.get(CameraCharacteristics.LENS_INFO_AVAILABLE_FOCAL_LENGTHS);
        SizeF physical = cc.get(CameraCharacteristics.SENSOR_INFO_PHYSICAL_SIZE);
        Size pixels = cc.get(CameraCharacteristics.SENSOR_INFO_PIXEL_ARRAY_SIZE);
        if (focal == null || focal.length == 0 || physical == null || pixels == null) {
            throw new IllegalArgumentException("Camera reports neither LENS_INTRINSIC_CALIBRATION nor focal length "
                    + "and sensor size: its intrinsics are unknown.");
        }
        return IntrinsicsCalculator.fromFocalLength(focal[0], physical.getWidth(), physical.getHeight(),
                new PixelSize(pixels.getWidth(), pixels.getHeight()), source, out, distortion, device);
    }

    private void startSession(final CameraCharacteristics cc, final Float focusDiopters, final boolean correctionOff,
                              final String summary) {
        try {
            camera.createCaptureSession(Collections.singletonList(reader.getSurface()),
                    new CameraCaptureSession.StateCallback() {
                        @Override
                        public void onConfigured(CameraCaptureSession s) {
                            session = s;
                            try {
                                CaptureRequest pose = request(cc, focusDiopters, correctionOff, settings, null);
                                if (idSettings == null) {
                                    s.setRepeatingRequest(pose, captureCallback, handler);
                                } else {
                                    CaptureRequest id = request(cc, focusDiopters, correctionOff, idSettings, ID_TAG);
                                    List<CaptureRequest> burst = new ArrayList<CaptureRequest>();
                                    burst.add(pose);
                                    burst.addAll(Collections.nCopies(ID_FRAMES_PER_POSE, id));
                                    s.setRepeatingBurst(burst, captureCallback, handler);
                                }
                                listener.onStarted(summary);
                            } catch (CameraAccessException e) {
                                listener.onError("Could not start capturing: " + e.getMessage());
                            }
                        }

                        @Override
                        public void onConfigureFailed(CameraCaptureSession s) {
                            listener.onError("The camera refused the YUV_420_888 stream.");
                        }
                    }, handler);
        } catch (CameraAccessException e) {
            listener.onError("Could not configure the camera: " + e.getMessage());
        }
    }

    private CaptureRequest request(CameraCharacteristics cc, Float focusDiopters, boolean correctionOff,
                                   CaptureSettings settings, Object tag) throws CameraAccessException {
        CaptureRequest.Builder b = camera.createCaptureRequest(CameraDevice.TEMPLATE_MANUAL);
        b.addTarget(reader.getSurface());
        b.setTag(tag);
        b.set(CaptureRequest.CONTROL_MODE, CameraMetadata.CONTROL_MODE_AUTO);
        b.set(CaptureRequest.CONTROL_AE_MODE, CameraMetadata.CONTROL_AE_MODE_OFF);
        b.set(CaptureRequest.CONTROL_AF_MODE, CameraMetadata.CONTROL_AF_MODE_OFF);
        b.set(CaptureRequest.SENSOR_EXPOSURE_TIME, settings.exposureNs);
        if (settings.sensitivityIso != null) {
            b.set(CaptureRequest.SENSOR_SENSITIVITY, settings.sensitivityIso);
        }
        b.set(CaptureRequest.SENSOR_FRAME_DURATION, settings.frameDurationNs);
        if (focusDiopters != null) {
            b.set(CaptureRequest.LENS_FOCUS_DISTANCE, focusDiopters);
        }
        if (correctionOff) {
            b.set(CaptureRequest.DISTORTION_CORRECTION_MODE, CameraMetadata.DISTORTION_CORRECTION_MODE_OFF);
        }
        // Sharpening and denoising move the edge profile the server fits: off where the camera allows.
        if (contains(cc.get(CameraCharacteristics.EDGE_AVAILABLE_EDGE_MODES), CameraMetadata.EDGE_MODE_OFF)) {
            b.set(CaptureRequest.EDGE_MODE, CameraMetadata.EDGE_MODE_OFF);
        }
        if (contains(cc.get(CameraCharacteristics.NOISE_REDUCTION_AVAILABLE_NOISE_REDUCTION_MODES),
                CameraMetadata.NOISE_REDUCTION_MODE_OFF)) {
            b.set(CaptureRequest.NOISE_REDUCTION_MODE, CameraMetadata.NOISE_REDUCTION_MODE_OFF);
        }
        return b.build();
    }

    private final CameraCaptureSession.CaptureCallback captureCallback = new CameraCaptureSession.CaptureCallback() {
        @Override
        public void onCaptureCompleted(CameraCaptureSession s, CaptureRequest request, TotalCaptureResult result) {
            Long ts = result.get(android.hardware.camera2.CaptureResult.SENSOR_TIMESTAMP);
            if (ts == null) {
                return;
            }
            captureValues.put(ts, new CaptureValues(
                    result.get(android.hardware.camera2.CaptureResult.SENSOR_EXPOSURE_TIME),
                    result.get(android.hardware.camera2.CaptureResult.SENSOR_SENSITIVITY),
                    result.get(android.hardware.camera2.CaptureResult.SENSOR_ROLLING_SHUTTER_SKEW), ts,
                    ID_TAG.equals(request.getTag())));
            while (captureValues.size() > MAX_CAPTURE_VALUES) {
                captureValues.remove(captureValues.keySet().iterator().next());
            }
            if (pendingLuma != null && pendingTimestampNs == ts) {
                emit(pendingLuma, captureValues.get(ts), pendingGravity, pendingRotation);
            }
        }
    };

    private void deliver(ImageReader r) {
        Image image = r.acquireLatestImage();
        if (image == null) {
            return;
        }
        try {
            if (!gate.wantFrame() || assembler == null) {
                return;
            }
            Image.Plane y = image.getPlanes()[0];
            byte[] luma = LumaPlane.copy(y.getBuffer(), image.getWidth(), image.getHeight(), y.getRowStride(),
                    y.getPixelStride());
            CaptureValues values = captureValues.get(image.getTimestamp());
            if (values != null) {
                emit(luma, values, gravity.latestGravity(), gravity.latestRotationToEnu());
            } else {
                // The result (exposure used, skew, pose or ID) comes later: wait for it; a newer frame replaces this.
                pendingLuma = luma;
                pendingTimestampNs = image.getTimestamp();
                pendingGravity = gravity.latestGravity();
                pendingRotation = gravity.latestRotationToEnu();
            }
        } catch (IllegalArgumentException e) {
            listener.onError("Frame dropped: " + e.getMessage());
        } finally {
            image.close();
        }
    }

    private void emit(byte[] luma, CaptureValues values, float[] gravityDevice, float[] deviceToEnu) {
        pendingLuma = null;
        pendingGravity = null;
        pendingRotation = null;
        try {
            listener.onFrame(luma, assembler.assemble(values, gravityDevice, deviceToEnu));
        } catch (IllegalArgumentException e) {
            listener.onError("Frame dropped: " + e.getMessage());
        }
    }
}
