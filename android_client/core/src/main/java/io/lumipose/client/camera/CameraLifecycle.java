package io.lumipose.client.camera;

/**
 * When to close the camera device and when to end the camera thread, as a state machine the
 * Camera2 controller follows (all calls on the camera thread). The rules that keep a camera from
 * staying open: a stop that comes while {@code openCamera} is in flight closes the device when
 * {@code onOpened} brings it; the thread quits only after the device's {@code onClosed} (or at once
 * when no device was ever opened), so no callback reaches a dead looper.
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
    private boolean closing;
    private boolean quit;

    /** openCamera was called. */
    public void opening() {
        opening = true;
    }

    public Action onOpened() {
        opening = false;
        if (closing) {
            return Action.CLOSE_DEVICE;
        }
        open = true;
        return Action.USE_DEVICE;
    }

    /** stop(): close what is open, or wait for what is opening. */
    public Action stop() {
        if (closing) {
            return Action.WAIT;
        }
        closing = true;
        if (open) {
            open = false;
            return Action.CLOSE_DEVICE;
        }
        return opening ? Action.WAIT : quit();
    }

    public Action onClosed() {
        open = false;
        return closing ? quit() : Action.WAIT;
    }

    /** onDisconnected or onError: the device is closed by the controller; a failed device may never report onClosed. */
    public Action onFailed() {
        opening = false;
        open = false;
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
