package io.lumipose.app;

import static org.junit.Assert.assertEquals;
import static org.junit.Assert.assertNotNull;
import static org.junit.Assert.assertTrue;
import static org.robolectric.Shadows.shadowOf;

import android.Manifest;
import android.app.Application;
import android.hardware.camera2.CaptureRequest;
import android.media.ImageReader;
import android.os.Looper;

import java.nio.charset.StandardCharsets;
import java.nio.file.Files;
import java.nio.file.Paths;

import org.junit.After;
import org.junit.Test;
import org.junit.runner.RunWith;
import org.robolectric.Robolectric;
import org.robolectric.RobolectricTestRunner;
import org.robolectric.RuntimeEnvironment;
import org.robolectric.android.controller.ActivityController;
import org.robolectric.annotation.Config;
import org.robolectric.annotation.GraphicsMode;

import io.lumipose.app.camera.FakeCamera;
import io.lumipose.app.camera.ShadowBurstSession;
import io.lumipose.app.camera.ShadowResultKeysCharacteristics;
import io.lumipose.app.camera.ShadowYuvImageReader;
import io.lumipose.client.camera.Devices;
import io.lumipose.client.calibration.CalibrationSession;
import io.lumipose.client.testutil.Repo;

/**
 * The calibration screen with its camera running (FakeCamera): it asks for the board's exposure
 * on the positioning plan's geometry, shows the camera's picture under the coverage grid, and is
 * pictured for docs/android.md.
 */
@RunWith(RobolectricTestRunner.class)
@GraphicsMode(GraphicsMode.Mode.NATIVE)
@Config(qualifiers = "w360dp-h740dp-xhdpi",
        shadows = {ShadowBurstSession.class, ShadowYuvImageReader.class, ShadowResultKeysCharacteristics.class})
public class CalibrationScreenTest {
    private FakeServer server;

    @After
    public void stop() {
        if (server != null) {
            server.close();
        }
    }

    /** A board of 7 x 5 squares, as the default spec prints it, filling the middle of the picture. */
    private static byte[] board(int width, int height) {
        byte[] luma = new byte[width * height];
        int square = Math.min(width / 9, height / 7);
        int left = (width - 7 * square) / 2;
        int top = (height - 5 * square) / 2;
        for (int y = 0; y < height; y++) {
            for (int x = 0; x < width; x++) {
                int i = Math.floorDiv(x - left, square);
                int j = Math.floorDiv(y - top, square);
                boolean onBoard = i >= 0 && i < 7 && j >= 0 && j < 5;
                luma[y * width + x] = (byte) (onBoard && (i + j) % 2 == 0 ? 30 : onBoard ? 220 : 120);
            }
        }
        return luma;
    }

    @Test
    public void showsTheCameraUnderTheCoverageGrid() throws Exception {
        Application app = RuntimeEnvironment.getApplication();
        shadowOf(app).grantPermissions(Manifest.permission.CAMERA);
        String map = new String(Files.readAllBytes(Paths.get(Repo.root().toString(), "shared_schemas/maps/demo.json")),
                StandardCharsets.UTF_8);
        server = new FakeServer().answer("GET /v1/maps/", 200, map);
        new Prefs(app).edit().putString(Prefs.SERVER_URL, server.url()).commit();
        FakeCamera camera = FakeCamera.install(app, Devices.load(Devices.PRE_CORRECTION));
        ActivityController<CameraCalibrationActivity> screen =
                Robolectric.buildActivity(CameraCalibrationActivity.class).setup();
        ShadowBurstSession session = camera.awaitBurst(10_000);
        CaptureRequest request = session.burst().get(0);
        assertEquals("the board's exposure", CalibrationSession.BOARD_EXPOSURE_NS,
                (long) request.get(CaptureRequest.SENSOR_EXPOSURE_TIME));
        assertEquals(CalibrationSession.BOARD_ISO, (int) request.get(CaptureRequest.SENSOR_SENSITIVITY));
        ImageReader reader = ShadowYuvImageReader.latest().reader();
        int w = reader.getWidth();
        int h = reader.getHeight();
        byte[] board = board(w, h);
        for (int i = 0; i < 12; i++) {
            camera.capture(session, 0, board, w, h, false);
        }
        shadowOf(Looper.getMainLooper()).idle();
        CameraCalibrationActivity calibration = screen.get();
        assertTrue(calibration.status.getText().toString(), calibration.status.getText().toString()
                .startsWith("Capturing"));
        assertNotNull("the camera's picture is shown", calibration.preview.shown());
        Screenshots.save(calibration, "android-calibration");
        screen.pause();
    }
}
