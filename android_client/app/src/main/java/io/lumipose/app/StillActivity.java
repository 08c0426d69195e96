package io.lumipose.app;

import android.view.View;
import android.widget.Button;
import android.widget.LinearLayout;

import java.util.concurrent.ExecutorService;
import java.util.concurrent.atomic.AtomicBoolean;

import io.lumipose.client.camera.CameraFacts;
import io.lumipose.client.capture.CapturePlan;
import io.lumipose.client.capture.FrameDescriber;
import io.lumipose.client.flow.FrameSink;
import io.lumipose.client.flow.StillCapture;
import io.lumipose.client.frame.FrameMeta;
import io.lumipose.client.frame.GreyPreview;

/**
 * A camera screen that takes still photos (the calibration board, the ceiling for a survey)
 * through the core's {@link StillCapture}: a preview of what the camera sees, and a shutter that
 * takes the next frame the describer keeps, whole, described as any positioning frame. Photos
 * reach {@link #onPhoto} on the screen's executor, one at a time.
 */
abstract class StillActivity extends CameraActivity implements StillCapture.Listener {
    /**
     * A preview about five times a second: enough to aim, little work on the camera thread. Below
     * the still plan's 200 ms frame period (CaptureOptions.STILL_BURSTS_PER_S), so that timestamp
     * jitter does not skip every other frame.
     */
    private static final long PREVIEW_EVERY_NS = 150_000_000L;
    protected PreviewView preview;
    protected Button shutter;
    protected volatile CameraFacts facts;
    private volatile StillCapture capture;
    private final AtomicBoolean photoInFlight = new AtomicBoolean();

    /** The describer of this screen's photos (the map's bearing; a calibration or not). */
    protected abstract FrameDescriber describer(CameraFacts facts, CapturePlan plan);

    /** The shutter button was pressed (UI thread). */
    protected abstract void onShutter();

    /**
     * Adds the preview (with the screen's overlay, filling the free height) and a row of the shutter
     * and the screen's action button (disabled until the screen enables it) to {@code root}.
     *
     * @return the action button
     */
    protected Button addCameraViews(LinearLayout root, PreviewView.Overlay overlay, String actionText,
                                    final Runnable action) {
        preview = new PreviewView(this);
        preview.setOverlay(overlay);
        shutter = new Button(this);
        shutter.setText("Take photo");
        shutter.setOnClickListener(new View.OnClickListener() {
            @Override
            public void onClick(View v) {
                onShutter();
            }
        });
        Button act = new Button(this);
        act.setText(actionText);
        act.setEnabled(false);
        act.setOnClickListener(new View.OnClickListener() {
            @Override
            public void onClick(View v) {
                action.run();
            }
        });
        LinearLayout buttons = new LinearLayout(this);
        buttons.addView(shutter);
        buttons.addView(act);
        root.addView(preview, new LinearLayout.LayoutParams(LinearLayout.LayoutParams.MATCH_PARENT, 0, 1f));
        root.addView(buttons);
        return act;
    }

    @Override
    protected FrameSink frameSink(CameraFacts facts, CapturePlan plan, ExecutorService network) {
        this.facts = facts;
        StillCapture c = new StillCapture(describer(facts, plan), gravity.history(), gravity.rates(),
                facts.timestampsAreRealtime(), network, this, PREVIEW_EVERY_NS);
        synchronized (sinkLock) {
            if (!current(network)) {
                c.close(); // the screen paused while it was built: onPause could not close it
                return null;
            }
            capture = c;
        }
        return c;
    }

    /**
     * Arms the shutter (UI thread): the shutter button stays off until the photo is handled (the
     * screen enables it again); says so when the camera is not running yet.
     */
    protected void takePhoto() {
        StillCapture c = capture;
        if (c != null && c.arm()) {
            shutter.setEnabled(false);
        } else {
            showStatus("The camera is not running yet.");
        }
    }

    /**
     * Closes the shutter's capture: an armed shot goes with the camera, so the shutter works again on
     * return (a photo already taken is being uploaded on the executor, which is shut down now: its
     * screen re-enables the shutter when the upload ends or is interrupted).
     */
    @Override
    protected void closeSinks() {
        StillCapture c;
        synchronized (sinkLock) {
            c = capture;
            capture = null;
        }
        if (c != null) {
            c.close();
        }
        if (!photoInFlight.get()) {
            shutter.setEnabled(true); // an armed shot went with the camera; a photo in flight enables it when done
        }
    }

    /** Any thread: the shutter on again after a photo the screen could not handle (the screen was left). */
    protected void shutterBack(final String why) {
        runOnUiThread(new Runnable() {
            @Override
            public void run() {
                shutter.setEnabled(true);
                if (why != null) {
                    showStatus(why);
                }
            }
        });
    }

    @Override
    public void onPreview(final GreyPreview p) {
        runOnUiThread(new Runnable() {
            @Override
            public void run() {
                onPreviewShown(p);
            }
        });
    }

    /** UI thread: a new preview of the camera; shows it unless the screen holds a photo. */
    protected void onPreviewShown(GreyPreview p) {
        preview.show(p);
    }

    @Override
    public void onDropped(String reason) {
        showStatus("Waiting for a usable frame: " + reason);
    }

    /**
     * A photo on the screen's executor. While one is being handled (uploaded) the shutter stays off,
     * even across a pause: a second photo meanwhile would race the first for the session's order.
     */
    @Override
    public final void onPhoto(byte[] luma, FrameMeta meta) {
        photoInFlight.set(true);
        try {
            handlePhoto(luma, meta);
        } finally {
            photoInFlight.set(false);
        }
    }

    /** The screen's work on one photo (its executor); enables the shutter again when done. */
    protected abstract void handlePhoto(byte[] luma, FrameMeta meta);
}
