package io.lumipose.client.sensor;

/** The phone's latest attitude readings, as Android's sensors report them. */
public interface GravitySource {
    /** A copy of the latest TYPE_GRAVITY [x, y, z], device frame, m/s^2 (pointing up), or null before the first. */
    float[] latestGravity();

    /** A copy of the latest device-to-East-North-Up rotation (row-major 3x3), or null when there is none. */
    float[] latestRotationToEnu();
}
