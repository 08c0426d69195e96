package io.lumipose.client.camera;

import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertTrue;

import org.junit.jupiter.api.Test;

import io.lumipose.client.camera.CameraLifecycle.Action;

/** Issue 12 item 6: stop() must not leave the camera open, nor quit the thread before the camera closes. */
class CameraLifecycleTest {
    @Test
    void aStopWhileOpeningClosesTheDeviceWhenItArrives() {
        CameraLifecycle l = new CameraLifecycle();
        l.opening();
        assertEquals(Action.WAIT, l.stop(), "the thread must live until onOpened");
        assertEquals(Action.CLOSE_DEVICE, l.onOpened(), "the late device is closed, not used");
        assertEquals(Action.QUIT, l.onClosed());
    }

    @Test
    void theThreadQuitsOnlyAfterOnClosed() {
        CameraLifecycle l = new CameraLifecycle();
        l.opening();
        assertEquals(Action.USE_DEVICE, l.onOpened());
        assertEquals(Action.CLOSE_DEVICE, l.stop());
        assertTrue(l.isClosing());
        assertEquals(Action.WAIT, l.stop(), "a second stop does nothing");
        assertEquals(Action.QUIT, l.onClosed());
        assertEquals(Action.WAIT, l.onClosed(), "quits once");
    }

    @Test
    void nothingOpenedQuitsAtOnce() {
        assertEquals(Action.QUIT, new CameraLifecycle().stop());
    }

    @Test
    void aFailedDeviceIsWaitedForUntilItsOnClosed() {
        CameraLifecycle l = new CameraLifecycle();
        l.opening();
        assertEquals(Action.WAIT, l.stop());
        assertEquals(Action.WAIT, l.onFailed(), "onError instead of onOpened: the closed device's onClosed comes next");
        assertEquals(Action.QUIT, l.onClosed());

        CameraLifecycle running = new CameraLifecycle();
        running.opening();
        running.onOpened();
        assertEquals(Action.WAIT, running.onFailed(), "disconnected while running: the screen is told, the thread stays");
        assertEquals(Action.WAIT, running.stop(), "its onClosed has not come yet");
        assertEquals(Action.QUIT, running.onClosed());
    }

    @Test
    void aCloseThatNeverReportsLetsTheThreadGoAfterTheTimeout() {
        CameraLifecycle l = new CameraLifecycle();
        l.opening();
        l.onOpened();
        assertEquals(Action.WAIT, l.onFailed());
        assertEquals(Action.WAIT, l.onCloseTimeout(), "not stopping: the thread stays for the screen");
        assertEquals(Action.WAIT, l.stop());
        assertEquals(Action.QUIT, l.onCloseTimeout());
        assertEquals(Action.WAIT, l.onClosed(), "quits once");
    }
}
