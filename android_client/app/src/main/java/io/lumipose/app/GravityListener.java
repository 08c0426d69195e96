package io.lumipose.app;

import android.content.Context;
import android.hardware.Sensor;
import android.hardware.SensorEvent;
import android.hardware.SensorEventListener;
import android.hardware.SensorManager;
import android.os.Handler;
import android.os.HandlerThread;

import io.lumipose.client.sensor.GravityHistory;
import io.lumipose.client.sensor.GyroHistory;
import io.lumipose.client.sensor.LowPassGravity;

/**
 * Feeds a GravityHistory with gravity (device frame, m/s^2, pointing up) and the rotation-vector
 * attitude (device to East-North-Up), each stamped with its event's timestamp, so every frame gets
 * the reading at its own SENSOR_TIMESTAMP. Phones without TYPE_GRAVITY get a low-passed accelerometer.
 * The gyroscope feeds a GyroHistory the same way: each frame gets the mean rate over its readout.
 *
 * <p>Events come on a thread of the listener's own (about 300 a second: gravity and rotation at
 * 50 Hz, the gyroscope at 200 Hz), started by {@link #start()} and ended by {@link #stop()}: on the
 * main thread they queued behind drawing and the screen's work, and delayed both. An event
 * allocates nothing: the rotation matrix and the low-passed gravity go through buffers of this
 * thread's, which the histories copy (they are read on the camera thread).
 */
final class GravityListener implements SensorEventListener {
    /**
     * 200 Hz: a readout lasts 10-40 ms, which GAME's 50 Hz could leave without a reading of its own.
     * It is the most an app gets without HIGH_SAMPLING_RATE_SENSORS; FASTEST (0 us) would throw a
     * SecurityException in a debuggable build on Android 12 and later.
     */
    private static final int GYROSCOPE_PERIOD_US = 5_000;
    private final SensorManager sensors;
    private final Sensor gravity;
    private final Sensor rotation;
    /** Null on a phone without one: frames go without angular_velocity_camera_dps. */
    private final Sensor gyroscope;
    /** Null when the phone has a gravity sensor. */
    private final LowPassGravity lowPass;
    private final GravityHistory history = new GravityHistory();
    private final GyroHistory rates = new GyroHistory();
    /** The sensor thread's buffers: the histories copy what they keep. */
    private final float[] rotationMatrix = new float[9];
    private final float[] filteredGravity = new float[3];
    /** Between start() and stop(); both on the main thread. */
    private HandlerThread thread;

    GravityListener(Context context) {
        sensors = (SensorManager) context.getSystemService(Context.SENSOR_SERVICE);
        Sensor fused = sensors == null ? null : sensors.getDefaultSensor(Sensor.TYPE_GRAVITY);
        Sensor accelerometer = sensors == null ? null : sensors.getDefaultSensor(Sensor.TYPE_ACCELEROMETER);
        gravity = fused != null ? fused : accelerometer;
        lowPass = fused == null && accelerometer != null ? new LowPassGravity() : null;
        rotation = sensors == null ? null : sensors.getDefaultSensor(Sensor.TYPE_ROTATION_VECTOR);
        gyroscope = sensors == null ? null : sensors.getDefaultSensor(Sensor.TYPE_GYROSCOPE);
    }

    /** Readings by timestamp; also the latest (a GravitySource). */
    GravityHistory history() {
        return history;
    }

    /** Gyroscope readings by timestamp (empty on a phone without one). */
    GyroHistory rates() {
        return rates;
    }

    /** False on a phone with neither a gravity sensor nor an accelerometer: frames go without gravity_camera. */
    boolean available() {
        return gravity != null;
    }

    /** Null, or what the screen should say about the gravity source. */
    String note() {
        if (gravity == null) {
            return "no gravity sensor or accelerometer: frames go without gravity";
        }
        return lowPass != null ? "no gravity sensor: gravity from the low-passed accelerometer" : null;
    }

    void start() {
        if (sensors == null || thread != null) {
            return;
        }
        thread = new HandlerThread("lumipose-sensors");
        thread.start();
        Handler handler = new Handler(thread.getLooper());
        if (gravity != null) {
            sensors.registerListener(this, gravity, SensorManager.SENSOR_DELAY_GAME, handler);
        }
        if (rotation != null) {
            sensors.registerListener(this, rotation, SensorManager.SENSOR_DELAY_GAME, handler);
        }
        if (gyroscope != null) {
            sensors.registerListener(this, gyroscope, GYROSCOPE_PERIOD_US, handler);
        }
    }

    void stop() {
        if (sensors == null || thread == null) {
            return;
        }
        sensors.unregisterListener(this);
        thread.quitSafely(); // events already queued still reach the histories
        thread = null;
    }

    /**
     * On the sensor thread. Synchronized only because a screen resumed at once may start the next
     * thread while the last one handles its last event: they share the buffers (uncontended otherwise).
     */
    @Override
    public synchronized void onSensorChanged(SensorEvent event) {
        switch (event.sensor.getType()) {
            case Sensor.TYPE_ROTATION_VECTOR:
                SensorManager.getRotationMatrixFromVector(rotationMatrix, event.values);
                history.addRotation(event.timestamp, rotationMatrix);
                break;
            case Sensor.TYPE_GRAVITY:
                history.addGravity(event.timestamp, event.values);
                break;
            case Sensor.TYPE_GYROSCOPE:
                rates.add(event.timestamp, event.values);
                break;
            case Sensor.TYPE_ACCELEROMETER:
                if (lowPass != null) {
                    history.addGravity(event.timestamp,
                            lowPass.update(event.timestamp, event.values, filteredGravity));
                }
                break;
            default:
                break;
        }
    }

    @Override
    public void onAccuracyChanged(Sensor sensor, int accuracy) {
        // The reading is used as it comes; the server weighs it by the device profile's sigma.
    }
}
