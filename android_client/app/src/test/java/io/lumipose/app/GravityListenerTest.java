package io.lumipose.app;

import static org.junit.Assert.assertArrayEquals;
import static org.junit.Assert.assertEquals;
import static org.junit.Assert.assertFalse;
import static org.junit.Assert.assertNotEquals;
import static org.junit.Assert.assertNotNull;
import static org.junit.Assert.assertSame;
import static org.junit.Assert.assertTrue;
import static org.robolectric.Shadows.shadowOf;

import android.content.Context;
import android.hardware.Sensor;
import android.hardware.SensorEvent;
import android.hardware.SensorEventListener;
import android.hardware.SensorManager;
import android.os.Handler;
import android.os.Looper;

import java.util.HashMap;
import java.util.Map;

import org.junit.Before;
import org.junit.Test;
import org.junit.runner.RunWith;
import org.robolectric.RobolectricTestRunner;
import org.robolectric.RuntimeEnvironment;
import org.robolectric.annotation.Implementation;
import org.robolectric.annotation.Implements;
import org.robolectric.shadows.SensorEventBuilder;
import org.robolectric.shadows.ShadowSensor;
import org.robolectric.shadows.ShadowSensorManager;

/**
 * Issue 26: about 300 sensor events a second are handled on a thread of the listener's own, not
 * the main thread (where they queued behind drawing and the screen's work), and land in the
 * histories, each kept as its own copy (the listener reuses its buffers).
 */
@RunWith(RobolectricTestRunner.class)
// The shadow is declared for every test in robolectric.properties.
public class GravityListenerTest {
    /**
     * Robolectric's SensorManager calls listeners on the caller's thread whatever Handler they gave;
     * this one keeps what each registration gave, so that the test delivers an event as Android
     * does: on the Handler's looper, or on the main looper without one.
     */
    @Implements(SensorManager.class)
    public static class HandlerRecordingSensorManager extends ShadowSensorManager {
        static final Map<Integer, Handler> HANDLERS = new HashMap<Integer, Handler>();
        static final Map<Integer, Integer> PERIODS_US = new HashMap<Integer, Integer>();

        @Override
        @Implementation
        protected boolean registerListener(SensorEventListener listener, Sensor sensor, int rate) {
            HANDLERS.put(sensor.getType(), null);
            PERIODS_US.put(sensor.getType(), rate);
            return super.registerListener(listener, sensor, rate);
        }

        @Override
        @Implementation
        protected boolean registerListener(SensorEventListener listener, Sensor sensor, int rate, Handler handler) {
            boolean registered = super.registerListener(listener, sensor, rate, handler); // records no handler
            HANDLERS.put(sensor.getType(), handler);
            return registered;
        }
    }

    private static final long T0 = 5_000_000_000L;
    private SensorManager sensors;
    private Sensor gravity;
    private Sensor rotation;
    private Sensor gyroscope;

    @Before
    public void phoneWithGravityRotationAndGyroscope() {
        HandlerRecordingSensorManager.HANDLERS.clear();
        HandlerRecordingSensorManager.PERIODS_US.clear();
        sensors = (SensorManager) RuntimeEnvironment.getApplication().getSystemService(Context.SENSOR_SERVICE);
        gravity = ShadowSensor.newInstance(Sensor.TYPE_GRAVITY);
        rotation = ShadowSensor.newInstance(Sensor.TYPE_ROTATION_VECTOR);
        gyroscope = ShadowSensor.newInstance(Sensor.TYPE_GYROSCOPE);
        shadowOf(sensors).addSensor(gravity);
        shadowOf(sensors).addSensor(rotation);
        shadowOf(sensors).addSensor(gyroscope);
    }

    /** Delivers the event as Android would for its registration; returns the thread that handled it. */
    private static Thread deliver(final SensorEventListener listener, final SensorEvent event) {
        Handler given = HandlerRecordingSensorManager.HANDLERS.get(event.sensor.getType());
        Looper looper = given == null ? Looper.getMainLooper() : given.getLooper();
        final Thread[] handledOn = new Thread[1];
        new Handler(looper).post(new Runnable() {
            @Override
            public void run() {
                handledOn[0] = Thread.currentThread();
                listener.onSensorChanged(event);
            }
        });
        shadowOf(looper).idle();
        assertNotNull("the event was handled", handledOn[0]);
        return handledOn[0];
    }

    private static SensorEvent event(Sensor sensor, long timestampNs, float... values) {
        return SensorEventBuilder.newBuilder().setSensor(sensor).setTimestamp(timestampNs).setValues(values).build();
    }

    @Test
    public void eventsAreHandledOffTheMainThreadAndLandInTheHistories() throws Exception {
        GravityListener listener = new GravityListener(RuntimeEnvironment.getApplication());
        listener.start();
        Thread main = Looper.getMainLooper().getThread();

        float half = (float) Math.sin(Math.toRadians(30) / 2);
        float[] turned = {0, 0, half, (float) Math.cos(Math.toRadians(30) / 2)}; // 30 deg about z
        Thread gravityThread = deliver(listener, event(gravity, T0, 0, 9.81f, 0));
        Thread rotationThread = deliver(listener, event(rotation, T0, turned));
        deliver(listener, event(rotation, T0 + 20_000_000L, 0, 0, 0, 1)); // the listener's matrix buffer again
        Thread gyroThread = deliver(listener, event(gyroscope, T0, 0.1f, 0.2f, 0.3f));

        assertNotEquals("not on the main thread", main, gravityThread);
        assertSame("one sensor thread", gravityThread, rotationThread);
        assertSame("one sensor thread", gravityThread, gyroThread);
        assertArrayEquals(new float[] {0, 9.81f, 0}, listener.history().gravityAt(T0), 0f);
        float[] expected = new float[9];
        SensorManager.getRotationMatrixFromVector(expected, turned);
        assertArrayEquals("the first rotation kept as its own copy", expected, listener.history().rotationAt(T0),
                0f);
        assertArrayEquals(new float[] {0.1f, 0.2f, 0.3f}, listener.rates().meanOver(T0, T0), 0f);

        // The same rates as before: gravity and attitude at GAME's 50 Hz, the gyroscope at 200 Hz.
        assertEquals(Integer.valueOf(SensorManager.SENSOR_DELAY_GAME),
                HandlerRecordingSensorManager.PERIODS_US.get(Sensor.TYPE_GRAVITY));
        assertEquals(Integer.valueOf(SensorManager.SENSOR_DELAY_GAME),
                HandlerRecordingSensorManager.PERIODS_US.get(Sensor.TYPE_ROTATION_VECTOR));
        assertEquals(Integer.valueOf(5_000), HandlerRecordingSensorManager.PERIODS_US.get(Sensor.TYPE_GYROSCOPE));

        listener.stop();
        assertFalse("unregistered", shadowOf(sensors).hasListener(listener));
        gravityThread.join(5_000);
        assertFalse("the sensor thread ends with stop()", gravityThread.isAlive());

        // A screen that resumes starts a thread of its own again.
        listener.start();
        Thread again = deliver(listener, event(gyroscope, T0 + 1_000_000_000L, 1, 1, 1));
        assertNotEquals(main, again);
        assertTrue(again.isAlive());
        assertArrayEquals(new float[] {1, 1, 1}, listener.rates().meanOver(T0 + 1_000_000_000L,
                T0 + 1_000_000_000L), 0f);
        listener.stop();
    }
}
