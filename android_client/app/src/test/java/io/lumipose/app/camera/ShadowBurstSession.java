package io.lumipose.app.camera;

import android.hardware.camera2.CameraCaptureSession;
import android.hardware.camera2.CaptureRequest;
import android.os.Handler;

import java.util.ArrayList;
import java.util.Collections;
import java.util.List;

import org.robolectric.annotation.Implementation;
import org.robolectric.annotation.Implements;
import org.robolectric.annotation.RealObject;
import org.robolectric.annotation.Resetter;
import org.robolectric.shadows.ShadowCameraCaptureSessionImpl;

/**
 * Robolectric's capture session knows single repeating requests only: this one also takes the
 * repeating burst the app asks for, and stops it, and remembers them so {@link FakeCamera} can
 * answer each request as a camera would. The newest session is {@link #latest()}.
 */
@Implements(className = "android.hardware.camera2.impl.CameraCaptureSessionImpl")
public class ShadowBurstSession extends ShadowCameraCaptureSessionImpl {
    private static volatile ShadowBurstSession latest;

    @RealObject
    private CameraCaptureSession session;
    private List<CaptureRequest> burst = Collections.emptyList();
    private CameraCaptureSession.CaptureCallback callback;
    private Handler handler;
    private volatile boolean closed;
    private int repeatingCalls;

    @Implementation
    protected int setRepeatingBurst(List<CaptureRequest> requests, CameraCaptureSession.CaptureCallback callback,
                                    Handler handler) {
        synchronized (this) {
            this.burst = new ArrayList<CaptureRequest>(requests);
            this.callback = callback;
            this.handler = handler;
            repeatingCalls++;
        }
        latest = this;
        return repeatingCalls;
    }

    @Implementation
    protected void stopRepeating() {
        synchronized (this) {
            burst = Collections.emptyList();
        }
    }

    @Implementation
    protected void abortCaptures() {
        stopRepeating();
    }

    @Override
    @Implementation
    protected void close() {
        closed = true;
        stopRepeating();
        super.close();
    }

    public synchronized List<CaptureRequest> burst() {
        return burst;
    }

    public synchronized CameraCaptureSession.CaptureCallback callback() {
        return callback;
    }

    public synchronized Handler handler() {
        return handler;
    }

    public CameraCaptureSession session() {
        return session;
    }

    public boolean closed() {
        return closed;
    }

    /** The session that most recently started a repeating burst, or null. */
    public static ShadowBurstSession latest() {
        return latest;
    }

    @Resetter
    public static void reset() {
        latest = null;
    }
}
