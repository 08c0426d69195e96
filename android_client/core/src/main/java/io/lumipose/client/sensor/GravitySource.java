package io.lumipose.client.sensor;

/** The latest gravity reading, device frame, m/s^2, as Android's TYPE_GRAVITY reports it (pointing up). */
public interface GravitySource {
    /** A copy of the latest [x, y, z], or null before the first reading. */
    float[] latestGravity();
}
