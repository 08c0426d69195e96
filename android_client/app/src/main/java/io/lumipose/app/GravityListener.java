package io.lumipose.app;

import android.content.Context;
import android.hardware.Sensor;
import android.hardware.SensorEvent;
import android.hardware.SensorEventListener;
import android.hardware.SensorManager;

import io.lumipose.client.sensor.GravitySource;

/**
 * Keeps the latest TYPE_GRAVITY reading (device frame, m/s^2, pointing up) and the latest
 * rotation-vector attitude (device to East-North-Up) for the frame JSON.
 */
final class GravityListener implements SensorEventListener, GravitySource {
    private final SensorManager sensors;
    private final Sensor gravity;
    private final Sensor rotation;
    private final Object lock = new Object();
    private float[] latest;
    private float[] latestRotation;

    GravityListener(Context context) {
        sensors = (SensorManager) context.getSystemService(Context.SENSOR_SERVICE);
        gravity = sensors == null ? null : sensors.getDefaultSensor(Sensor.TYPE_GRAVITY);
        rotation = sensors == null ? null : sensors.getDefaultSensor(Sensor.TYPE_ROTATION_VECTOR);
    }

    /** False on a phone without a gravity sensor: frames then go without gravity_camera. */
    boolean available() {
        return gravity != null;
    }

    void start() {
        if (gravity != null) {
            sensors.registerListener(this, gravity, SensorManager.SENSOR_DELAY_GAME);
        }
        if (rotation != null) {
            sensors.registerListener(this, rotation, SensorManager.SENSOR_DELAY_UI);
        }
    }

    void stop() {
        if (sensors != null) {
            sensors.unregisterListener(this);
        }
        synchronized (lock) {
            latest = null;
            latestRotation = null;
        }
    }

    @Override
    public void onSensorChanged(SensorEvent event) {
        if (event.sensor.getType() == Sensor.TYPE_ROTATION_VECTOR) {
            float[] m = new float[9];
            SensorManager.getRotationMatrixFromVector(m, event.values);
            synchronized (lock) {
                latestRotation = m;
            }
            return;
        }
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

    @Override
    public float[] latestRotationToEnu() {
        synchronized (lock) {
            return latestRotation == null ? null : latestRotation.clone();
        }
    }
}
