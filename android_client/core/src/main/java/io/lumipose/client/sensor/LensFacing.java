package io.lumipose.client.sensor;

/** Which way the lens looks relative to the screen (Camera2 {@code LENS_FACING}). */
public enum LensFacing {
    /** Looks out of the back, along -z of the device frame. */
    BACK,
    /** Looks out of the screen side, along +z of the device frame. */
    FRONT
}
