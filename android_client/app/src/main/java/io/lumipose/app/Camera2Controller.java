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
import android.hardware.camera2.CaptureResult;
import android.hardware.camera2.TotalCaptureResult;
import android.hardware.camera2.params.TonemapCurve;
import android.media.Image;
import android.media.ImageReader;
import android.os.Handler;
import android.os.HandlerThread;

import java.util.ArrayList;
import java.util.Collections;
import java.util.List;

import io.lumipose.client.camera.CameraFacts;
import io.lumipose.client.camera.CameraLifecycle;
import io.lumipose.client.camera.FrameResult;
import io.lumipose.client.capture.CaptureOptions;
import io.lumipose.client.capture.CapturePlan;
import io.lumipose.client.capture.RequestSpec;
import io.lumipose.client.capture.UnsupportedCameraException;
import io.lumipose.client.flow.FrameSink;

/**
 * The only code that holds the camera: a thin adapter. It reads the characteristics into
 * CameraFacts, lets the core plan the capture (CapturePlan), turns the plan's RequestSpecs into
 * CaptureRequests (a repeating burst: the pose frame, then the ID frames), and hands every
 * TotalCaptureResult (as a FrameResult) and every Y plane to the FrameSink the listener returns.
 * It decides nothing and copies no frame.
 *
 * <p>Lifecycle: everything runs on one HandlerThread. {@link #stop()} closes what is open; an
 * {@code onOpened} still in flight closes its device on arrival, and the thread quits only after
 * the device's {@code onClosed}, so no callback reaches a dead looper and no camera stays open.
 */
final class Camera2Controller {
    /** Told what happens; every call comes on the camera thread. */
    interface Listener {
        /**
         * The plan to capture with, from the positioning plan (the calibration screen swaps in the
         * board's exposure; the others keep it). On the camera thread, before anything is opened.
         */
        CapturePlan plan(CameraFacts facts, CapturePlan positioning) throws UnsupportedCameraException;

        /** The camera is configured; returns where frames go (the Activity builds it from facts and plan). */
        FrameSink onStarted(CameraFacts facts, CapturePlan plan, String summary);

        /** The camera cannot be used on this phone or by this app (no retry helps). */
        void onUnsupported(String reason);

        /**
         * The camera was lost or failed (disconnected, taken by another app, an error, a refused
         * stream, an exception on the camera thread): everything is closed and the controller opens
         * it again by itself in {@code retryInMs}.
         */
        void onCameraLost(String message, long retryInMs);

        /** Capturing again after {@link #onCameraLost}, into the same sink. */
        void onCameraBack(String summary);

        /** A frame could not be handled (the sink threw): the frame is dropped, capturing goes on. */
        void onFrameError(String message);
    }

    /** Images in flight: the sink copies during the call, so a few suffice for a five-frame burst. */
    private static final int MAX_IMAGES = 4;
    /** Reopening after a loss: the first wait, doubled each time up to the last. */
    static final long FIRST_RETRY_MS = 1000;
    static final long LAST_RETRY_MS = 30_000;
    /**
     * White balance runs until it has converged (or this many frames have passed, for a camera that
     * never says so), then is locked: gains that move from frame to frame would move the Y levels the
     * server's clipped-edge model reads, and gains locked before they settle could be far off.
     */
    static final int AWB_SETTLE_MAX_FRAMES = 30;

    private final Context context;
    private final String requestedCameraId;
    private final CaptureOptions options;
    private final Listener listener;

    private HandlerThread thread;
    private Handler handler;
    /** UI thread: stop() was called. */
    private boolean stopRequested;
    // Camera thread only from here on.
    /** How long a closing device may take to report onClosed before the thread quits anyway. */
    private static final long CLOSE_TIMEOUT_MS = 3000;
    private final CameraLifecycle lifecycle = new CameraLifecycle();
    private CameraDevice camera;
    private CameraCaptureSession session;
    private ImageReader reader;
    private FrameSink sink;
    /** The facts and plan of the camera being used (kept across reopenings). */
    private CameraFacts facts;
    private CapturePlan plan;
    private String summary;
    private boolean awbLocked;
    private int framesSinceConfigured;
    /** openCamera calls so far: each one's callbacks know whether they are still the current device's. */
    private int openings;
    /** The wait before the next reopening; 0 until a loss. */
    private long retryMs;
    private boolean lost;
    /** Only the first of a run of failing frames is told: a broken sink would say so every frame. */
    private boolean frameErrorTold;

    Camera2Controller(Context context, String cameraId, CaptureOptions options, Listener listener) {
        this.context = context.getApplicationContext();
        this.requestedCameraId = cameraId;
        this.options = options;
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

    void start() {
        if (thread != null) {
            return;
        }
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

    /** Closes the camera; the thread ends after the camera says it is closed. Safe to call twice. */
    void stop() {
        if (handler == null || stopRequested) {
            return;
        }
        stopRequested = true;
        handler.post(new Runnable() {
            @Override
            public void run() {
                close();
            }
        });
    }

    private void close() {
        sink = null;
        closeSession();
        // With openCamera in flight this waits: onOpened closes the device, whose onClosed quits.
        act(lifecycle.stop(), camera);
        // A device closed after an error may never report onClosed: the thread goes after a while anyway.
        handler.postDelayed(new Runnable() {
            @Override
            public void run() {
                act(lifecycle.onCloseTimeout(), null);
            }
        }, CLOSE_TIMEOUT_MS);
    }

    /** Closing a session the camera already dropped may throw: it is gone either way. */
    private void closeSession() {
        CameraCaptureSession s = session;
        session = null;
        if (s != null) {
            try {
                s.close();
            } catch (RuntimeException alreadyGone) {
                // closed underneath us (the device failed or was closed first)
            }
        }
    }

    private void act(CameraLifecycle.Action action, CameraDevice device) {
        if (action == CameraLifecycle.Action.CLOSE_DEVICE) {
            camera = null;
            device.close();
        } else if (action == CameraLifecycle.Action.QUIT) {
            quit();
        }
    }

    /** The reader goes last: the closed camera writes no more into its surface. */
    private void quit() {
        if (reader != null) {
            reader.close();
            reader = null;
        }
        thread.quitSafely();
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
        if (lifecycle.isClosing()) {
            return;
        }
        if (context.checkSelfPermission(Manifest.permission.CAMERA) != PackageManager.PERMISSION_GRANTED) {
            listener.onUnsupported("Camera permission not granted.");
            return;
        }
        CameraManager manager = (CameraManager) context.getSystemService(Context.CAMERA_SERVICE);
        try {
            if (facts == null) {
                String id = chooseCameraId(manager);
                if (id == null) {
                    listener.onUnsupported("This phone has no camera.");
                    return;
                }
                CameraCharacteristics cc = manager.getCameraCharacteristics(id);
                CameraFacts read = CameraFactsReader.read(id, cc);
                CapturePlan p = CapturePlan.plan(read, options);
                if (!CameraFactsReader.reportsRollingShutterSkew(cc)) {
                    p = p.withoutIdFrames("no rolling-shutter skew: beacon IDs off");
                }
                plan = listener.plan(read, p);
                facts = read;
                summary = summary(facts, plan);
            }
            if (reader == null) {
                reader = ImageReader.newInstance(plan.output.width, plan.output.height, ImageFormat.YUV_420_888,
                        MAX_IMAGES);
                reader.setOnImageAvailableListener(new ImageReader.OnImageAvailableListener() {
                    @Override
                    public void onImageAvailable(ImageReader r) {
                        deliver(r);
                    }
                }, handler);
            }
            manager.openCamera(facts.cameraId, stateCallback(), handler);
            lifecycle.opening(); // callbacks come on this thread, after this method returns
        } catch (UnsupportedCameraException e) {
            listener.onUnsupported(e.getMessage());
        } catch (IllegalArgumentException e) {
            listener.onUnsupported("Camera facts unusable: " + e.getMessage());
        } catch (SecurityException e) {
            listener.onUnsupported("Camera permission refused: " + e.getMessage());
        } catch (CameraAccessException e) {
            if (e.getReason() == CameraAccessException.CAMERA_DISABLED) {
                listener.onUnsupported("The camera is disabled on this phone (device policy).");
            } else {
                lose("Camera not available (" + accessReason(e) + ")");
            }
        } catch (RuntimeException e) {
            lose("Camera failed to open: " + e);
        }
    }

    private static String accessReason(CameraAccessException e) {
        switch (e.getReason()) {
            case CameraAccessException.CAMERA_IN_USE:
                return "in use by another app";
            case CameraAccessException.MAX_CAMERAS_IN_USE:
                return "too many cameras open";
            case CameraAccessException.CAMERA_DISCONNECTED:
                return "disconnected";
            default:
                return e.getMessage();
        }
    }

    /**
     * The camera was lost: close what is open (the sink stays for the next try) and open again
     * after a wait that doubles each time, until stopped. A user who walks away from the phone and
     * back finds it capturing again without leaving the screen.
     */
    private void lose(String message) {
        closeSession();
        awbLocked = false;
        CameraDevice device = camera;
        if (device != null) {
            camera = null;
            device.close();
            act(lifecycle.onFailed(), device);
        }
        if (lifecycle.isClosing()) {
            return;
        }
        lost = true;
        retryMs = retryMs == 0 ? FIRST_RETRY_MS : Math.min(LAST_RETRY_MS, 2 * retryMs);
        listener.onCameraLost(message, retryMs);
        handler.removeCallbacks(reopen); // two losses in a row (an error, then its device's disconnect): one retry
        handler.postDelayed(reopen, retryMs);
    }

    private final Runnable reopen = new Runnable() {
        @Override
        public void run() {
            open();
        }
    };

    private CameraDevice.StateCallback stateCallback() {
        final int generation = ++openings;
        return new CameraDevice.StateCallback() {
            /** A device of an earlier opening (failed, then reopened): closed, but the lifecycle is the new one's. */
            private boolean stale() {
                return generation != openings;
            }

            @Override
            public void onOpened(CameraDevice device) {
                if (stale()) {
                    device.close();
                    return;
                }
                if (lifecycle.onOpened() == CameraLifecycle.Action.USE_DEVICE) {
                    camera = device;
                    startSession();
                } else {
                    device.close(); // stop() came while opening
                }
            }

            @Override
            public void onClosed(CameraDevice device) {
                if (!stale()) {
                    act(lifecycle.onClosed(), device);
                }
            }

            @Override
            public void onDisconnected(CameraDevice device) {
                if (stale()) {
                    device.close();
                    return;
                }
                failed(device, "Camera disconnected (another app may have taken it)");
            }

            @Override
            public void onError(CameraDevice device, int error) {
                if (stale()) {
                    device.close();
                } else if (error == CameraDevice.StateCallback.ERROR_CAMERA_DISABLED) {
                    failed(device, null);
                    listener.onUnsupported("The camera is disabled on this phone (device policy).");
                } else {
                    failed(device, "Camera error " + error + " (" + errorName(error) + ")");
                }
            }
        };
    }

    private static String errorName(int error) {
        switch (error) {
            case CameraDevice.StateCallback.ERROR_CAMERA_IN_USE:
                return "in use";
            case CameraDevice.StateCallback.ERROR_MAX_CAMERAS_IN_USE:
                return "too many cameras open";
            case CameraDevice.StateCallback.ERROR_CAMERA_DEVICE:
                return "device failed";
            case CameraDevice.StateCallback.ERROR_CAMERA_SERVICE:
                return "camera service failed";
            default:
                return "unknown";
        }
    }

    /** A device that failed: closed; reopened later unless stopping or {@code message} is null. */
    private void failed(CameraDevice device, String message) {
        closeSession();
        if (camera == device) {
            camera = null;
        }
        device.close();
        act(lifecycle.onFailed(), device);
        if (message != null) {
            lose(message);
        }
    }

    private void startSession() {
        try {
            camera.createCaptureSession(Collections.singletonList(reader.getSurface()),
                    new CameraCaptureSession.StateCallback() {
                        @Override
                        public void onConfigured(CameraCaptureSession s) {
                            if (lifecycle.isClosing() || camera == null) {
                                return;
                            }
                            session = s;
                            try {
                                framesSinceConfigured = 0;
                                awbLocked = false;
                                repeat(s);
                                started();
                            } catch (CameraAccessException | RuntimeException e) {
                                lose("Could not start capturing: " + e.getMessage());
                            }
                        }

                        @Override
                        public void onConfigureFailed(CameraCaptureSession s) {
                            if (!lifecycle.isClosing()) {
                                lose("The camera refused the YUV_420_888 stream");
                            }
                        }
                    }, handler);
        } catch (CameraAccessException | RuntimeException e) {
            lose("Could not configure the camera: " + e.getMessage());
        }
    }

    /**
     * The sink is made once, on the first configuration that succeeds (also when earlier attempts
     * failed: the camera was busy when the screen opened); a later reopening only says it is back.
     */
    private void started() {
        boolean wasLost = lost;
        lost = false;
        retryMs = 0;
        if (sink == null) {
            sink = listener.onStarted(facts, plan, summary);
        } else if (wasLost) {
            listener.onCameraBack(summary);
        }
    }

    /** (Re)starts the repeating burst, with white balance locked once it has settled. */
    private void repeat(CameraCaptureSession s) throws CameraAccessException {
        List<CaptureRequest> burst = new ArrayList<CaptureRequest>();
        for (RequestSpec spec : plan.burst()) {
            burst.add(request(spec, awbLocked));
        }
        s.setRepeatingBurst(burst, captureCallback, handler);
    }

    /** One RequestSpec as a CaptureRequest: every value comes from the spec; "null" leaves a key alone. */
    private CaptureRequest request(RequestSpec spec, boolean lockWhiteBalance) throws CameraAccessException {
        CaptureRequest.Builder b = camera.createCaptureRequest(CameraDevice.TEMPLATE_MANUAL);
        b.addTarget(reader.getSurface());
        b.setTag(spec.kind);
        b.set(CaptureRequest.CONTROL_MODE, CameraMetadata.CONTROL_MODE_AUTO);
        b.set(CaptureRequest.CONTROL_AE_MODE, CameraMetadata.CONTROL_AE_MODE_OFF);
        b.set(CaptureRequest.CONTROL_AF_MODE, CameraMetadata.CONTROL_AF_MODE_OFF);
        // Auto white balance until it settles, then the gains stay where they are (AWB_SETTLE_MAX_FRAMES).
        b.set(CaptureRequest.CONTROL_AWB_MODE, CameraMetadata.CONTROL_AWB_MODE_AUTO);
        b.set(CaptureRequest.CONTROL_AWB_LOCK, lockWhiteBalance);
        // Digital stabilisation crops and shifts the stream: the intrinsics assume neither.
        b.set(CaptureRequest.CONTROL_VIDEO_STABILIZATION_MODE, CameraMetadata.CONTROL_VIDEO_STABILIZATION_MODE_OFF);
        b.set(CaptureRequest.SENSOR_EXPOSURE_TIME, spec.exposureNs);
        if (spec.sensitivityIso != null) {
            b.set(CaptureRequest.SENSOR_SENSITIVITY, spec.sensitivityIso);
        }
        b.set(CaptureRequest.SENSOR_FRAME_DURATION, spec.frameDurationNs);
        if (spec.focusDiopters != null) {
            b.set(CaptureRequest.LENS_FOCUS_DISTANCE, spec.focusDiopters);
        }
        b.set(CaptureRequest.SCALER_CROP_REGION, new Rect(spec.cropRegion.left, spec.cropRegion.top,
                spec.cropRegion.left + spec.cropRegion.width, spec.cropRegion.top + spec.cropRegion.height));
        if (spec.oisOff) {
            b.set(CaptureRequest.LENS_OPTICAL_STABILIZATION_MODE, CameraMetadata.LENS_OPTICAL_STABILIZATION_MODE_OFF);
        }
        float[] curve = spec.toneCurve();
        if (curve != null) {
            b.set(CaptureRequest.TONEMAP_MODE, CameraMetadata.TONEMAP_MODE_CONTRAST_CURVE);
            b.set(CaptureRequest.TONEMAP_CURVE, new TonemapCurve(curve, curve, curve));
        } else if (spec.srgbPreset) {
            // A known curve where no contrast curve is offered: the frames say "srgb" and the server undoes it.
            b.set(CaptureRequest.TONEMAP_MODE, CameraMetadata.TONEMAP_MODE_PRESET_CURVE);
            b.set(CaptureRequest.TONEMAP_PRESET_CURVE, CameraMetadata.TONEMAP_PRESET_CURVE_SRGB);
        }
        if (spec.edgeOff) {
            b.set(CaptureRequest.EDGE_MODE, CameraMetadata.EDGE_MODE_OFF);
        }
        if (spec.noiseReductionOff) {
            b.set(CaptureRequest.NOISE_REDUCTION_MODE, CameraMetadata.NOISE_REDUCTION_MODE_OFF);
        }
        if (spec.distortionCorrectionOff) {
            b.set(CaptureRequest.DISTORTION_CORRECTION_MODE, CameraMetadata.DISTORTION_CORRECTION_MODE_OFF);
        }
        if (Camera2Keys.available()) {
            if (spec.rotateAndCropNone) {
                b.set(Camera2Keys.REQUEST_ROTATE_AND_CROP, Camera2Keys.ROTATE_AND_CROP_NONE);
            }
            if (facts.zoomRatioRange() != null) {
                b.set(Camera2Keys.REQUEST_ZOOM_RATIO, 1f);
            }
        }
        return b.build();
    }

    private static String summary(CameraFacts facts, CapturePlan plan) {
        StringBuilder s = new StringBuilder("camera ").append(facts.cameraId).append(", ").append(plan.output)
                .append(", pose ").append(plan.pose.exposureNs / 1000).append(" us ISO ")
                .append(plan.pose.sensitivityIso);
        if (plan.id != null) {
            s.append(", ").append(plan.idFramesPerBurst).append(" ID frames ").append(plan.id.exposureNs / 1000)
                    .append(" us ISO ").append(plan.id.sensitivityIso);
        }
        for (String note : plan.notes) {
            s.append("; ").append(note);
        }
        return s.toString();
    }

    private final CameraCaptureSession.CaptureCallback captureCallback = new CameraCaptureSession.CaptureCallback() {
        @Override
        public void onCaptureCompleted(CameraCaptureSession s, CaptureRequest request, TotalCaptureResult result) {
            if (s != session) {
                return; // a late result of a session closed since
            }
            settleWhiteBalance(s, result);
            FrameSink to = sink;
            if (to == null) {
                return;
            }
            try {
                FrameResult frame = FrameResultReader.read(result);
                if (frame != null) {
                    to.onResult(frame);
                }
                frameErrorTold = false;
            } catch (RuntimeException e) {
                frameFailed("capture result", e);
            }
        }
    };

    /** Locks white balance once it has converged, or after AWB_SETTLE_MAX_FRAMES frames. */
    private void settleWhiteBalance(CameraCaptureSession s, TotalCaptureResult result) {
        if (awbLocked) {
            return;
        }
        Integer state = result.get(CaptureResult.CONTROL_AWB_STATE);
        framesSinceConfigured++;
        if ((state != null && state == CameraMetadata.CONTROL_AWB_STATE_CONVERGED)
                || framesSinceConfigured >= AWB_SETTLE_MAX_FRAMES) {
            awbLocked = true;
            try {
                repeat(s);
            } catch (CameraAccessException | RuntimeException e) {
                lose("Could not lock white balance: " + e.getMessage());
            }
        }
    }

    private void frameFailed(String what, RuntimeException e) {
        if (!frameErrorTold) {
            frameErrorTold = true;
            listener.onFrameError("A frame's " + what + " could not be handled (" + e + "): frame dropped.");
        }
    }

    private void deliver(ImageReader r) {
        Image image;
        try {
            image = r.acquireNextImage();
        } catch (RuntimeException e) {
            // IllegalStateException: more images held than maxImages, or the reader closed meanwhile
            frameFailed("image", e);
            return;
        }
        if (image == null) {
            return;
        }
        try {
            FrameSink to = sink;
            if (to != null) {
                Image.Plane y = image.getPlanes()[0];
                to.onImage(image.getTimestamp(), y.getBuffer(), image.getWidth(), image.getHeight(),
                        y.getRowStride(), y.getPixelStride());
            }
        } catch (RuntimeException e) {
            frameFailed("image", e);
        } finally {
            image.close();
        }
    }
}
