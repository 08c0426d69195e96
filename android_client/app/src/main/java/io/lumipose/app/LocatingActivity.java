package io.lumipose.app;

import java.util.Collections;
import java.util.List;
import java.util.Map;
import java.util.concurrent.ExecutorService;

import io.lumipose.client.camera.CameraFacts;
import io.lumipose.client.capture.CapturePlan;
import io.lumipose.client.capture.FrameDescriber;
import io.lumipose.client.flow.FramePipeline;
import io.lumipose.client.flow.FrameSink;
import io.lumipose.client.frame.FrameMeta;
import io.lumipose.client.net.LocateResult;
import io.lumipose.client.net.LumiposeClient;

/**
 * A camera screen that streams bursts to POST /v1/locate through the core's FramePipeline (one
 * burst in flight, the beacon's window only, in the map this screen draws). Subclasses get pose
 * results only: an ID frame's answer is never a position to show or track.
 */
abstract class LocatingActivity extends CameraActivity implements FramePipeline.Listener {
    private volatile FramePipeline pipeline;
    protected volatile CapturePlan plan;

    /** A pose frame's answer, on the upload thread. */
    protected abstract void onPose(FrameMeta meta, LocateResult result);

    @Override
    protected FrameSink frameSink(CameraFacts facts, CapturePlan plan, ExecutorService network) {
        this.plan = plan;
        // live frames: one attempt, a short timeout, no gzip, the map this screen draws
        LumiposeClient live = LumiposeClient.create(prefs.liveConfig());
        // the map's bearing for the heading, and this camera's calibration when it has one
        FrameDescriber describer = new FrameDescriber(facts, plan, mapBearingDeg(),
                prefs.calibratedProfile(facts.cameraId));
        FramePipeline p = FramePipeline.forCamera(describer, facts, plan, gravity.history(), gravity.rates(), live,
                network, this);
        synchronized (sinkLock) {
            if (!current(network)) {
                p.close(); // the screen paused while it was built: onPause could not close it
                return null;
            }
            pipeline = p;
        }
        return p;
    }

    @Override
    protected void closeSinks() {
        FramePipeline p;
        synchronized (sinkLock) {
            p = pipeline;
            pipeline = null;
        }
        if (p != null) {
            p.close();
        }
    }

    /** Frames not sent so far, by reason (empty before the camera starts). */
    protected Map<String, Long> dropCounts() {
        FramePipeline p = pipeline;
        return p == null ? Collections.<String, Long>emptyMap() : p.dropCounts();
    }

    /** The frame describer's warnings so far, each once. */
    protected List<String> warnings() {
        FramePipeline p = pipeline;
        return p == null ? Collections.<String>emptyList() : p.warnings();
    }

    @Override
    public final void onPoseResult(FrameMeta meta, LocateResult result) {
        onPose(meta, result);
    }

    @Override
    public void onIdResult(FrameMeta meta, LocateResult result) {
        // The server keeps the stripes for the device's next pose frame; its answer here is no position.
    }

    @Override
    public void onDropped(String reason) {
    }

    @Override
    public void onFailure(FrameMeta meta, Exception error) {
        showStatus("Upload failed: " + error.getMessage());
    }
}
