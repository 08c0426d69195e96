package io.lumipose.app;

import android.Manifest;
import android.app.Activity;
import android.content.pm.PackageManager;
import android.os.Bundle;
import android.view.WindowManager;
import android.widget.TextView;

import java.util.concurrent.ExecutorService;
import java.util.concurrent.Executors;

import io.lumipose.client.capture.CaptureSettingsChooser;
import io.lumipose.client.frame.FrameMeta;
import io.lumipose.client.map.RoomMap;
import io.lumipose.client.net.LumiposeClient;

/**
 * What every camera screen shares: permission, the camera controller, the gravity listener, the
 * server client on a background executor, and the room map. Subclasses only lay out and react.
 */
abstract class CameraActivity extends Activity implements Camera2Controller.Listener, Camera2Controller.FrameGate {
    private static final int PERMISSION_REQUEST = 1;

    protected Prefs prefs;
    protected LumiposeClient client;
    protected ExecutorService network;
    protected GravityListener gravity;
    protected TextView status;
    protected volatile RoomMap map;
    private Camera2Controller controller;
    // The permission dialog pauses and resumes the screen: ask once, and start the camera once.
    private boolean permissionAsked;

    /** The screen's content; {@link #status} is already created. */
    protected abstract void buildViews();

    /** A frame the gate let through, on the camera thread. */
    protected abstract void handleFrame(byte[] luma, FrameMeta meta);

    /** The exposure this screen captures at. */
    protected long exposureNs() {
        return CaptureSettingsChooser.POSITION_EXPOSURE_NS;
    }

    /** Short-exposure beacon-ID frames beside the pose frames: 0 for none (one-beacon screens). */
    protected long idExposureNs() {
        return 0;
    }

    @Override
    protected void onCreate(Bundle savedInstanceState) {
        super.onCreate(savedInstanceState);
        getWindow().addFlags(WindowManager.LayoutParams.FLAG_KEEP_SCREEN_ON);
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
        network = Executors.newSingleThreadExecutor();
        gravity.start();
        loadMap();
        if (checkSelfPermission(Manifest.permission.CAMERA) == PackageManager.PERMISSION_GRANTED) {
            startCamera();
        } else if (!permissionAsked) {
            permissionAsked = true;
            requestPermissions(new String[] {Manifest.permission.CAMERA}, PERMISSION_REQUEST);
        } else {
            showStatus("Lumipose needs the camera to see the ceiling panel: allow it in the app's settings.");
        }
    }

    @Override
    public void onRequestPermissionsResult(int requestCode, String[] permissions, int[] results) {
        if (requestCode == PERMISSION_REQUEST && results.length > 0
                && results[0] == PackageManager.PERMISSION_GRANTED) {
            startCamera();
        } else {
            showStatus("Lumipose needs the camera to see the ceiling panel.");
        }
    }

    private void startCamera() {
        if (controller != null || network == null) {
            return;
        }
        controller = new Camera2Controller(this, prefs.cameraId(), exposureNs(), idExposureNs(), prefs.focusDistanceM(),
                prefs.mapXBearingDeg(), (long) (prefs.maxMegapixels() * 1e6), gravity, this, this);
        controller.start();
    }

    @Override
    protected void onPause() {
        if (controller != null) {
            controller.stop();
            controller = null;
        }
        if (gravity != null) {
            gravity.stop();
        }
        if (network != null) {
            network.shutdownNow();
            network = null;
        }
        super.onPause();
    }

    private void loadMap() {
        final String name = prefs.mapName();
        network.execute(new Runnable() {
            @Override
            public void run() {
                try {
                    map = client.fetchMap(name);
                    onMapLoaded(map);
                } catch (Exception e) {
                    showStatus("Map '" + name + "' not loaded: " + e.getMessage());
                }
            }
        });
    }

    /** Called on a background thread once the map is in. */
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

    @Override
    public void onStarted(String summary) {
        showStatus("Capturing: " + summary + (gravity.available() ? "" : " (no gravity sensor)"));
    }

    @Override
    public void onUnsupported(String reason) {
        showStatus("Camera not usable: " + reason);
    }

    @Override
    public void onError(String message) {
        showStatus(message);
    }

    @Override
    public void onFrame(byte[] luma, FrameMeta meta) {
        handleFrame(luma, meta);
    }
}
