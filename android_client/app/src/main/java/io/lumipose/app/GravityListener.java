package io.lumipose.app;

import android.content.Context;
import android.hardware.Sensor;
import android.hardware.SensorEvent;
import android.hardware.SensorEventListener;
import android.hardware.SensorManager;

import io.lumipose.client.sensor.GravitySource;

/** Keeps the latest TYPE_GRAVITY reading (device frame, m/s^2, pointing up) for the frame JSON. */
final class GravityListener implements SensorEventListener, GravitySource {
    private final SensorManager sensors;
    private final Sensor gravity;
    private final Object lock = new Object();
    private float[] latest;

    GravityListener(Context context) {
        sensors = (SensorManager) context.getSystemService(Context.SENSOR_SERVICE);
        gravity = sensors == null ? null : sensors.getDefaultSensor(Sensor.TYPE_GRAVITY);
    }

    /** False on a phone without a gravity sensor: frames then go without gravity_camera. */
    boolean available() {
        return gravity != null;
    }

    void start() {
        if (gravity != null) {
            sensors.registerListener(this, gravity, SensorManager.SENSOR_DELAY_GAME);
        }
    }

    void stop() {
        if (gravity != null) {
            sensors.unregisterListener(this);
        }
        synchronized (lock) {
            latest = null;
        }
    }

    @Override
    public void onSensorChanged(SensorEvent event) {
        synchronized (lock) {
            latest = new float[] {event.values[0], event.values[1], event.values[2]};
        }
    }

    @Override
    public void onAccuracyChanged(Sensor sensor, int accuracy) {
        // The reading is used as it comes; the server weighs it by the device profile's sigma.
    }

    @Override
    public float[] latestGravity() {
        synchronized (lock) {
            return latest == null ? null : latest.clone();
        }
    }
}
