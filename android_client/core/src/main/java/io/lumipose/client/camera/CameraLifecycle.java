package io.lumipose.client.camera;

/**
 * When to close the camera device and when to end the camera thread, as a state machine the
 * Camera2 controller follows (all calls on the camera thread). The rules that keep a camera from
 * staying open: a stop that comes while {@code openCamera} is in flight closes the device when
 * {@code onOpened} brings it; the thread quits only after the device's {@code onClosed} (at once
 * when no device was ever opened; after a timeout when a failed device never reports it), so no
 * callback reaches a dead looper.
 */
public final class CameraLifecycle {
    /** What the controller must do now. */
    public enum Action {
        /** Nothing yet: wait for the next callback. */
        WAIT,
        /** Use the device (it just opened and nobody is stopping). */
        USE_DEVICE,
        /** Close the device; its onClosed comes next. */
        CLOSE_DEVICE,
        /** Release the reader and quit the camera thread. */
        QUIT
    }

    private boolean opening;
    private boolean open;
    /** close() was called on a device (by stop, or after a failure) and its onClosed has not come yet. */
    private boolean deviceClosing;
    private boolean closing;
    private boolean quit;

    /** openCamera was called. */
    public void opening() {
        opening = true;
    }

    public Action onOpened() {
        opening = false;
        if (closing) {
            deviceClosing = true;
            return Action.CLOSE_DEVICE;
        }
        open = true;
        return Action.USE_DEVICE;
    }

    /** stop(): close what is open, or wait for what is opening or closing. */
    public Action stop() {
        if (closing) {
            return Action.WAIT;
        }
        closing = true;
        if (open) {
            open = false;
            deviceClosing = true;
            return Action.CLOSE_DEVICE;
        }
        return opening || deviceClosing ? Action.WAIT : quit();
    }

    public Action onClosed() {
        open = false;
        deviceClosing = false;
        return closing ? quit() : Action.WAIT;
    }

    /**
     * onDisconnected or onError: the controller has closed the device, whose onClosed comes next;
     * the thread waits for it like any close.
     */
    public Action onFailed() {
        opening = false;
        open = false;
        deviceClosing = true;
        return Action.WAIT;
    }

    /**
     * A close that never reported onClosed (some HALs after an error), past the controller's
     * patience: the thread goes anyway once stopping.
     */
    public Action onCloseTimeout() {
        return closing ? quit() : Action.WAIT;
    }

    public boolean isClosing() {
        return closing;
    }

    private Action quit() {
        if (quit) {
            return Action.WAIT;
        }
        quit = true;
        return Action.QUIT;
    }
}
