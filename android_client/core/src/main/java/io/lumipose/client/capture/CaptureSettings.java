package io.lumipose.client.capture;

import java.util.ArrayList;
import java.util.Collections;
import java.util.List;

/** Manual values for one repeating request; {@code notes} says what had to be clamped or left out. */
public final class CaptureSettings {
    public final long exposureNs;
    /** Null when the camera advertises no sensitivity range: ISO is then left to the device. */
    public final Integer sensitivityIso;
    public final long frameDurationNs;
    public final List<String> notes;

    public CaptureSettings(long exposureNs, Integer sensitivityIso, long frameDurationNs, List<String> notes) {
        this.exposureNs = exposureNs;
        this.sensitivityIso = sensitivityIso;
        this.frameDurationNs = frameDurationNs;
        this.notes = Collections.unmodifiableList(new ArrayList<String>(notes));
    }

    public double exposureS() {
        return exposureNs / 1e9;
    }
}
