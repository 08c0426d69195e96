package io.lumipose.app;

import android.Manifest;
import android.app.Activity;
import android.content.pm.PackageManager;
import android.os.Bundle;
import android.view.WindowManager;
import android.widget.TextView;

import java.util.concurrent.ExecutorService;
import java.util.concurrent.Executors;
import java.util.concurrent.RejectedExecutionException;

import io.lumipose.client.camera.CameraFacts;
import io.lumipose.client.capture.CaptureOptions;
import io.lumipose.client.capture.CapturePlan;
import io.lumipose.client.capture.UnsupportedCameraException;
import io.lumipose.client.flow.FrameSink;
import io.lumipose.client.map.RoomMap;
import io.lumipose.client.net.LumiposeClient;
import io.lumipose.client.protocol.CaptureProtocol;

/**
 * What every camera screen shares: permission, the map, the camera controller, the gravity
 * history and a background executor this screen owns (made in onResume, shut down in onPause,
 * never used after). The camera starts only once the map is in: the capture plan needs its beacon
 * count (ID bursts only with more than one beacon) and its ceiling (focus).
 */
abstract class CameraActivity extends Activity implements Camera2Controller.Listener {
    private static final int PERMISSION_REQUEST = 1;
    private static final String PERMISSION_ASKED = "lumipose.permission_asked";

    protected Prefs prefs;
    /** Map fetches and stored samples: patient (retries, long timeout). */
    protected LumiposeClient client;
    protected GravityListener gravity;
    protected TextView status;
    protected volatile RoomMap map;
    // written on the UI thread (under sinkLock), read on the camera thread (onStarted): volatile
    private volatile ExecutorService network;
    /**
     * Held by a screen while it keeps the sink it built on the camera thread and while onPause takes
     * the executor away: a sink built for an executor that is gone is closed at once, never kept.
     */
    protected final Object sinkLock = new Object();
    /** The screen is kept on and the sensors run: only while the camera may run (resumed, allowed). */
    private boolean cameraMayRun;
    private Camera2Controller controller;
    // The permission dialog pauses and resumes the screen: ask once, and start the camera once. Kept
    // across recreation: the dialog outlives the screen and answers the recreated one.
    private boolean permissionAsked;
    private boolean cameraAllowed;

    /** The screen's content; {@link #status} is already created. */
    protected abstract void buildViews();

    /**
     * Where this screen's frames go, for the camera just configured (on the camera thread); the
     * executor is the screen's network executor.
     */
    protected abstract FrameSink frameSink(CameraFacts facts, CapturePlan plan, ExecutorService network);

    /** Short-exposure beacon-ID frames after each pose frame: 0 for none. */
    protected long idExposureNs() {
        return 0;
    }

    @Override
    protected void onCreate(Bundle savedInstanceState) {
        super.onCreate(savedInstanceState);
        permissionAsked = savedInstanceState != null && savedInstanceState.getBoolean(PERMISSION_ASKED);
        prefs = new Prefs(this);
        status = new TextView(this);
        status.setPadding(16, 16, 16, 16);
        buildViews();
        try {
            client = LumiposeClient.create(prefs.clientConfig());
        } catch (IllegalArgumentException e) {
            showStatus("Settings: " + e.getMessage());
        }
        gravity = new GravityListener(this);
    }

    @Override
    protected void onResume() {
        super.onResume();
        if (client == null) {
            return;
        }
        synchronized (sinkLock) {
            network = Executors.newSingleThreadExecutor();
        }
        if (checkSelfPermission(Manifest.permission.CAMERA) == PackageManager.PERMISSION_GRANTED) {
            cameraAllowed = true;
            cameraMayRun();
        } else if (!permissionAsked) {
            permissionAsked = true;
            requestPermissions(new String[] {Manifest.permission.CAMERA}, PERMISSION_REQUEST);
        } else {
            showStatus("Lumipose needs the camera to see the ceiling panel: allow it in the app's settings.");
        }
        loadMap();
    }

    @Override
    public void onRequestPermissionsResult(int requestCode, String[] permissions, int[] results) {
        if (requestCode == PERMISSION_REQUEST && results.length > 0
                && results[0] == PackageManager.PERMISSION_GRANTED) {
            cameraAllowed = true;
            if (network != null) { // resumed (the answer may also come just before onResume)
                cameraMayRun();
            }
            startCameraWhenReady();
        } else {
            showStatus("Lumipose needs the camera to see the ceiling panel.");
        }
    }

    /** UI thread, resumed with the permission: the screen stays on and the sensors run (once). */
    private void cameraMayRun() {
        if (!cameraMayRun) {
            cameraMayRun = true;
            getWindow().addFlags(WindowManager.LayoutParams.FLAG_KEEP_SCREEN_ON);
            gravity.start();
        }
    }

    @Override
    protected void onSaveInstanceState(Bundle outState) {
        super.onSaveInstanceState(outState);
        outState.putBoolean(PERMISSION_ASKED, permissionAsked);
    }

    /** UI thread: starts the camera once both the permission and the map are there. */
    private void startCameraWhenReady() {
        RoomMap m = map;
        if (controller != null || network == null || !cameraAllowed || m == null) {
            return;
        }
        CaptureOptions options;
        try {
            options = new CaptureOptions(CaptureProtocol.POSE_EXPOSURE_NS, idExposureNs(), m.beacons.size(),
                    prefs.ceilingDistanceM(m), (long) (prefs.maxMegapixels() * 1e6));
        } catch (IllegalArgumentException e) {
            showStatus("Settings: " + e.getMessage());
            return;
        }
        controller = new Camera2Controller(this, prefs.cameraId(), options, this);
        controller.start();
    }

    @Override
    protected void onPause() {
        ExecutorService gone;
        synchronized (sinkLock) {
            gone = network;
            network = null; // from now on a sink built on the camera thread is closed at once
        }
        closeSinks();
        if (controller != null) {
            controller.stop();
            controller = null;
        }
        if (cameraMayRun) {
            cameraMayRun = false;
            getWindow().clearFlags(WindowManager.LayoutParams.FLAG_KEEP_SCREEN_ON);
            gravity.stop();
        }
        if (gone != null) {
            gone.shutdownNow();
        }
        super.onPause();
    }

    /**
     * UI thread, in onPause once the executor is taken away (before the camera stops): closes the
     * screen's sinks (taken out under {@link #sinkLock}) and puts its buttons back.
     */
    protected void closeSinks() {
    }

    /**
     * Whether a sink the camera thread built for executor {@code e} may be kept: the screen has not
     * paused since (nor resumed again with another executor). Call holding {@link #sinkLock}, and keep
     * the sink (or close it) in the same block.
     */
    protected final boolean current(ExecutorService e) {
        return e != null && e == network;
    }

    /**
     * Runs a task on this screen's executor; false when the screen is paused (the executor shut
     * down or gone), so nothing is ever handed to a dead executor.
     */
    protected boolean inBackground(Runnable task) {
        ExecutorService e = network;
        if (e == null) {
            return false;
        }
        try {
            e.execute(task);
            return true;
        } catch (RejectedExecutionException shutDown) {
            return false;
        }
    }

    private void loadMap() {
        final String name = prefs.mapName();
        inBackground(new Runnable() {
            @Override
            public void run() {
                try {
                    final RoomMap loaded = client.fetchMap(name);
                    map = loaded;
                    onMapLoaded(loaded);
                    runOnUiThread(new Runnable() {
                        @Override
                        public void run() {
                            startCameraWhenReady();
                        }
                    });
                } catch (InterruptedException e) {
                    Thread.currentThread().interrupt();
                } catch (Exception e) {
                    showStatus("Map '" + name + "' not loaded: " + e.getMessage());
                }
            }
        });
    }

    /** Called on a background thread once the map is in, before the camera starts. */
    protected void onMapLoaded(RoomMap loaded) {
    }

    protected void showStatus(final String text) {
        runOnUiThread(new Runnable() {
            @Override
            public void run() {
                status.setText(text);
            }
        });
    }

    /** The positioning plan as it is; a screen that photographs something else changes its exposure. */
    @Override
    public CapturePlan plan(CameraFacts facts, CapturePlan positioning) throws UnsupportedCameraException {
        return positioning;
    }

    /**
     * The compass bearing of the map's +X axis for the frames' heading: the map's own (a survey
     * measured it), else the one typed in the settings, else none.
     */
    protected Double mapBearingDeg() {
        RoomMap m = map;
        return m == null ? prefs.mapXBearingDeg() : m.bearingOr(prefs.mapXBearingDeg());
    }

    @Override
    public FrameSink onStarted(CameraFacts facts, CapturePlan plan, String summary) {
        ExecutorService e = network;
        if (e == null) {
            return null; // paused meanwhile: the controller is being stopped
        }
        showStatus("Capturing: " + summary + (gravity.available() ? "" : " (no gravity sensor)"));
        return frameSink(facts, plan, e);
    }

    @Override
    public void onUnsupported(String reason) {
        showStatus("Camera not usable: " + reason);
    }

    @Override
    public void onCameraLost(String message, long retryInMs) {
        showStatus(message + ": trying again in " + (retryInMs + 500) / 1000 + " s.");
    }

    @Override
    public void onCameraBack(String summary) {
        showStatus("Capturing again: " + summary);
    }

    @Override
    public void onFrameError(String message) {
        showStatus(message);
    }
}
