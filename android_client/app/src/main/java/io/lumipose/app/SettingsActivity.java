package io.lumipose.app;

import android.app.Activity;
import android.os.Bundle;
import android.text.InputType;
import android.view.View;
import android.widget.ArrayAdapter;
import android.widget.Button;
import android.widget.CheckBox;
import android.widget.EditText;
import android.widget.LinearLayout;
import android.widget.ScrollView;
import android.widget.Spinner;
import android.widget.TextView;

import java.util.ArrayList;
import java.util.List;

import io.lumipose.client.net.LumiposeClient;

/** Server URL, API key, map, camera and capture options. */
public final class SettingsActivity extends Activity {
    private static final int TEXT = InputType.TYPE_CLASS_TEXT;
    private static final int DECIMAL = InputType.TYPE_CLASS_NUMBER | InputType.TYPE_NUMBER_FLAG_DECIMAL;
    // Fixed view ids: what the user typed (or ticked, or chose) survives the screen's recreation.
    private static final int ID_URL = 1;
    private static final int ID_KEY = 2;
    private static final int ID_MAP = 3;
    private static final int ID_HAND = 4;
    private static final int ID_MEGAPIXELS = 5;
    private static final int ID_ID_EXPOSURE = 6;
    private static final int ID_BEARING = 7;
    private static final int ID_READ_IDS = 8;
    private static final int ID_CAMERA = 9;
    private Prefs prefs;
    private EditText url;
    private EditText key;
    private EditText mapName;
    private EditText handHeight;
    private EditText megapixels;
    private EditText idExposure;
    private EditText bearing;
    private Spinner camera;
    private CheckBox readIds;
    private final List<String> cameraIds = new ArrayList<String>();
    private TextView status;

    @Override
    protected void onCreate(Bundle savedInstanceState) {
        super.onCreate(savedInstanceState);
        prefs = new Prefs(this);
        LinearLayout form = new LinearLayout(this);
        form.setOrientation(LinearLayout.VERTICAL);
        form.setPadding(24, 24, 24, 24);
        url = field(form, ID_URL, "Server URL (http://host:port)", prefs.serverUrl(), TEXT | InputType.TYPE_TEXT_VARIATION_URI);
        key = field(form, ID_KEY, "API key (empty if the server has none)", prefs.apiKey(),
                TEXT | InputType.TYPE_TEXT_VARIATION_PASSWORD);
        mapName = field(form, ID_MAP, "Map name", prefs.mapName(), TEXT);
        handHeight = field(form, ID_HAND, "Phone's height above the floor, m (focus: the map's ceiling minus this)",
                String.valueOf(prefs.handHeightM()), DECIMAL);
        megapixels = field(form, ID_MEGAPIXELS, "Largest frame, megapixels", String.valueOf(prefs.maxMegapixels()), DECIMAL);
        idExposure = field(form, ID_ID_EXPOSURE, "Beacon-ID exposure, microseconds", String.valueOf(prefs.idExposureNs() / 1000),
                InputType.TYPE_CLASS_NUMBER);

        Double b = prefs.mapXBearingDeg();
        bearing = field(form, ID_BEARING, "Compass bearing of the map's +X axis, deg, for maps without a surveyed bearing "
                + "(empty: no heading then)",
                b == null ? "" : String.valueOf(b), DECIMAL | InputType.TYPE_NUMBER_FLAG_SIGNED);
        readIds = new CheckBox(this);
        readIds.setId(ID_READ_IDS);
        readIds.setText("Read beacon IDs in live mode (short-exposure frames after each pose frame, on maps "
                + "of several panels)");
        readIds.setChecked(prefs.readIds());
        form.addView(readIds);

        TextView cameraLabel = new TextView(this);
        cameraLabel.setText("Camera");
        form.addView(cameraLabel);
        camera = new Spinner(this);
        camera.setId(ID_CAMERA);
        List<String> labels = new ArrayList<String>();
        cameraIds.add("");
        labels.add("Automatic (first back camera with manual exposure)");
        int selected = 0;
        for (String[] c : Camera2Controller.describeCameras(this)) {
            cameraIds.add(c[0]);
            labels.add("Camera " + c[0] + " (" + c[1] + ")");
            if (c[0].equals(prefs.cameraId())) {
                selected = cameraIds.size() - 1;
            }
        }
        camera.setAdapter(new ArrayAdapter<String>(this, android.R.layout.simple_spinner_dropdown_item, labels));
        camera.setSelection(selected);
        form.addView(camera);

        Button save = new Button(this);
        save.setText("Save and test the connection");
        save.setOnClickListener(new View.OnClickListener() {
            @Override
            public void onClick(View v) {
                save();
            }
        });
        form.addView(save);
        status = new TextView(this);
        form.addView(status);
        ScrollView scroll = new ScrollView(this);
        scroll.addView(form);
        setContentView(scroll);
    }

    private EditText field(LinearLayout form, int id, String label, String value, int inputType) {
        return Forms.field(this, form, id, label, value, inputType);
    }

    private void save() {
        float handM;
        float mp;
        long idUs;
        try {
            handM = Float.parseFloat(handHeight.getText().toString());
            mp = Float.parseFloat(megapixels.getText().toString());
            idUs = Long.parseLong(idExposure.getText().toString());
        } catch (NumberFormatException e) {
            status.setText("Height, megapixels and exposure must be numbers.");
            return;
        }
        if (!(handM >= 0) || !(mp > 0) || idUs <= 0) {
            status.setText("Height must be at least 0; megapixels and exposure positive.");
            return;
        }
        String bearingText = bearing.getText().toString().trim();
        if (!bearingText.isEmpty()) {
            try {
                Double.parseDouble(bearingText);
            } catch (NumberFormatException e) {
                status.setText("The map bearing must be a number of degrees, or empty.");
                return;
            }
        }
        prefs.edit().putString(Prefs.SERVER_URL, url.getText().toString().trim())
                .putString(Prefs.API_KEY, key.getText().toString().trim())
                .putString(Prefs.MAP_NAME, mapName.getText().toString().trim())
                .putString(Prefs.CAMERA_ID, cameraIds.get(camera.getSelectedItemPosition()))
                .putFloat(Prefs.HAND_HEIGHT_M, handM).putFloat(Prefs.MAX_MEGAPIXELS, mp)
                .putLong(Prefs.ID_EXPOSURE_US, idUs).putBoolean(Prefs.READ_IDS, readIds.isChecked())
                .putString(Prefs.MAP_X_BEARING_DEG, bearingText).apply();
        final LumiposeClient client;
        try {
            client = LumiposeClient.create(prefs.clientConfig());
        } catch (IllegalArgumentException e) {
            status.setText(e.getMessage());
            return;
        }
        status.setText("Saved. Testing the connection...");
        new Thread(new Runnable() {
            @Override
            public void run() {
                final boolean ok = client.healthy();
                runOnUiThread(new Runnable() {
                    @Override
                    public void run() {
                        status.setText(ok ? "Saved. The server answers." : "Saved, but the server does not answer "
                                + "/healthz: check the URL and that the phone is on the server's network.");
                    }
                });
            }
        }, "lumipose-health").start();
    }
}
