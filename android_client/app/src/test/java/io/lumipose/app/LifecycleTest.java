package io.lumipose.app;

import static org.junit.Assert.assertEquals;
import static org.junit.Assert.assertFalse;
import static org.junit.Assert.assertNotNull;
import static org.junit.Assert.assertNull;
import static org.junit.Assert.assertTrue;
import static org.robolectric.Shadows.shadowOf;

import android.Manifest;
import android.app.Activity;
import android.app.Application;
import android.content.Context;
import android.content.pm.PackageManager;
import android.hardware.Sensor;
import android.hardware.SensorManager;
import android.view.WindowManager;

import java.util.Arrays;
import java.util.List;
import java.util.concurrent.Callable;
import java.util.concurrent.ExecutorService;

import org.junit.Before;
import org.junit.Test;
import org.junit.runner.RunWith;
import org.robolectric.Robolectric;
import org.robolectric.RobolectricTestRunner;
import org.robolectric.RuntimeEnvironment;
import org.robolectric.android.controller.ActivityController;
import org.robolectric.shadows.ShadowActivity;
import org.robolectric.shadows.ShadowSensor;

import io.lumipose.client.flow.FrameSink;

/**
 * Every screen starts, survives recreate() and pause/resume, with the settings' default server
 * and one that refuses; the camera screens ask for the camera once, keep the screen on and the
 * sensors running only while the camera may run, and start working once the permission comes.
 */
@RunWith(RobolectricTestRunner.class)
public class LifecycleTest {
    static final List<Class<? extends CameraActivity>> CAMERA_SCREENS = Arrays.<Class<? extends CameraActivity>>asList(
            LiveActivity.class, AlignmentActivity.class, CameraCalibrationActivity.class, SurveyActivity.class,
            BenchActivity.class);
    static final List<Class<? extends Activity>> SCREENS = Arrays.asList(MainActivity.class, LiveActivity.class,
            AlignmentActivity.class, CameraCalibrationActivity.class, SurveyActivity.class, BenchActivity.class,
            SettingsActivity.class);
    private Application app;
    private SensorManager sensors;

    @Before
    public void setUp() {
        app = RuntimeEnvironment.getApplication();
        sensors = (SensorManager) app.getSystemService(Context.SENSOR_SERVICE);
        shadowOf(sensors).addSensor(ShadowSensor.newInstance(Sensor.TYPE_GRAVITY));
    }

    private static void cycle(ActivityController<? extends Activity> c) {
        c.recreate();
        c.pause().resume();
        c.recreate();
        c.pause().stop().destroy();
    }

    /** Prefs' default server (http://192.168.1.10:8000: a LAN address, likely nobody there). */
    @Test
    public void everyScreenLivesThroughRecreationWithTheDefaultServer() {
        shadowOf(app).grantPermissions(Manifest.permission.CAMERA);
        for (Class<? extends Activity> screen : SCREENS) {
            cycle(Robolectric.buildActivity(screen).setup());
        }
    }

    @Test
    public void everyScreenLivesThroughRecreationWithAServerThatRefuses() {
        shadowOf(app).grantPermissions(Manifest.permission.CAMERA);
        Screens.server(app, "http://127.0.0.1:1");
        for (Class<? extends Activity> screen : SCREENS) {
            ActivityController<? extends Activity> c = Robolectric.buildActivity(screen).setup();
            final Activity a = c.get();
            if (a instanceof CameraActivity) {
                Screens.settle(screen.getSimpleName() + " saying the map is not loaded", new Callable<Boolean>() {
                    @Override
                    public Boolean call() {
                        return Screens.text(a, "status").startsWith("Map 'test-bench' not loaded");
                    }
                });
            }
            cycle(c);
        }
    }

    @Test
    public void aBadServerUrlIsSaidAndNothingStarts() {
        shadowOf(app).grantPermissions(Manifest.permission.CAMERA);
        Screens.server(app, "not a url");
        for (Class<? extends CameraActivity> screen : CAMERA_SCREENS) {
            ActivityController<? extends CameraActivity> c = Robolectric.buildActivity(screen).setup();
            assertTrue(Screens.text(c.get(), "status"), Screens.text(c.get(), "status").startsWith("Settings: "));
            cycle(c);
        }
    }

    private boolean screenKeptOn(Activity a) {
        return (a.getWindow().getAttributes().flags & WindowManager.LayoutParams.FLAG_KEEP_SCREEN_ON) != 0;
    }

    private boolean sensing(CameraActivity a) {
        return shadowOf(sensors).hasListener(a.gravity);
    }

    @Test
    public void theCameraIsAskedForOnceEvenAcrossRecreation() {
        Screens.server(app, "http://127.0.0.1:1");
        for (Class<? extends CameraActivity> screen : CAMERA_SCREENS) {
            String name = screen.getSimpleName();
            shadowOf(app).denyPermissions(Manifest.permission.CAMERA);
            ActivityController<? extends CameraActivity> c = Robolectric.buildActivity(screen).setup();
            CameraActivity a = c.get();
            ShadowActivity.PermissionsRequest asked = shadowOf(a).getLastRequestedPermission();
            assertNotNull(name + " asks for the camera", asked);
            assertEquals(Manifest.permission.CAMERA, asked.requestedPermissions[0]);
            c.recreate(); // the dialog's answer comes to the recreated screen: it does not ask again
            a = c.get();
            assertNull(name + " asked again after recreation", shadowOf(a).getLastRequestedPermission());
            a.onRequestPermissionsResult(asked.requestCode, asked.requestedPermissions,
                    new int[] {PackageManager.PERMISSION_DENIED});
            Screens.settle(name + " saying why", statusStarts(a, "Lumipose needs the camera"));
            c.pause().resume();
            assertNull(name + " asked again after pause/resume", shadowOf(a).getLastRequestedPermission());
            assertTrue(Screens.text(a, "status"), Screens.text(a, "status").contains("allow it in the app's settings"));
            cycle(c);
        }
    }

    @Test
    public void theScreenStaysOnAndTheSensorsRunOnlyWhileTheCameraMay() {
        Screens.server(app, "http://127.0.0.1:1");
        for (Class<? extends CameraActivity> screen : CAMERA_SCREENS) {
            String name = screen.getSimpleName();
            shadowOf(app).denyPermissions(Manifest.permission.CAMERA);
            ActivityController<? extends CameraActivity> c = Robolectric.buildActivity(screen).setup();
            CameraActivity a = c.get();
            ShadowActivity.PermissionsRequest asked = shadowOf(a).getLastRequestedPermission();
            assertFalse(name + ": no camera, no reason to keep the screen on", screenKeptOn(a));
            assertFalse(name + ": no camera, no sensors", sensing(a));
            a.onRequestPermissionsResult(asked.requestCode, asked.requestedPermissions,
                    new int[] {PackageManager.PERMISSION_DENIED});
            c.recreate();
            a = c.get();
            assertFalse(screenKeptOn(a));
            assertFalse(sensing(a));

            shadowOf(app).grantPermissions(Manifest.permission.CAMERA);
            a.onRequestPermissionsResult(asked.requestCode, asked.requestedPermissions,
                    new int[] {PackageManager.PERMISSION_GRANTED});
            assertTrue(name + ": the camera may run now", screenKeptOn(a));
            assertTrue(name + ": sensors for the frames", sensing(a));
            c.pause();
            assertFalse(name + " paused", screenKeptOn(a));
            assertFalse(name + " paused", sensing(a));
            c.resume();
            assertTrue(screenKeptOn(a));
            assertTrue(sensing(a));
            cycle(c);
        }
    }

    private static Callable<Boolean> statusStarts(final Activity a, final String prefix) {
        return new Callable<Boolean>() {
            @Override
            public Boolean call() {
                return Screens.text(a, "status").startsWith(prefix);
            }
        };
    }

    /**
     * The camera thread read the screen's executor, then the screen paused (closing its sink, none
     * yet) before the sink was built: that sink is closed at once, never kept open.
     */
    @Test
    public void aSinkBuiltAfterThePauseIsClosedAtOnce() {
        shadowOf(app).grantPermissions(Manifest.permission.CAMERA);
        Screens.server(app, "http://127.0.0.1:1");
        Screens.Camera camera = new Screens.Camera();
        for (Class<? extends CameraActivity> screen : CAMERA_SCREENS) {
            String name = screen.getSimpleName();
            ActivityController<? extends CameraActivity> c = Robolectric.buildActivity(screen).setup();
            CameraActivity a = c.get();
            ExecutorService seen = Screens.get(a, "network");
            c.pause();
            FrameSink late;
            try {
                late = a.frameSink(camera.facts, a.plan(camera.facts, camera.positioning), seen);
            } catch (Exception e) {
                throw new AssertionError(e);
            }
            String field = a instanceof StillActivity ? "capture" : "pipeline";
            assertNull(name + " kept a sink built after its pause", Screens.get(a, field));
            if (late != null) {
                assertTrue(name + "'s late sink is not closed", closed(late));
            }
            c.resume();
            assertNull(name + ": the late sink is not the resumed camera's", Screens.get(a, field));
            FrameSink current = camera.start(a);
            assertNotNull(name, current);
            assertNotNull(name, Screens.get(a, field));
            assertFalse(name + ": the resumed camera's sink is open", closed(Screens.<FrameSink>get(a, field)));
            cycle(c);
        }
    }

    /** A pipeline's or a shutter's own flag; the bench's gate (in front of its pipeline, checked above): true. */
    private static boolean closed(FrameSink s) {
        if (s instanceof io.lumipose.client.flow.FramePipeline || s instanceof io.lumipose.client.flow.StillCapture) {
            return Screens.<Boolean>get(s, "closed");
        }
        return true;
    }
}
