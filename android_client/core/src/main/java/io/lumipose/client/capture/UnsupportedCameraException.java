package io.lumipose.client.capture;

/** The camera cannot take the manual frames positioning needs; the message says which capability is missing. */
public final class UnsupportedCameraException extends Exception {
    private static final long serialVersionUID = 1L;

    public UnsupportedCameraException(String message) {
        super(message);
    }
}
