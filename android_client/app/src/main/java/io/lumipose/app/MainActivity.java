package io.lumipose.app;

import android.app.Activity;
import android.content.Intent;
import android.os.Bundle;
import android.view.View;
import android.widget.Button;
import android.widget.LinearLayout;
import android.widget.TextView;

/** The modes. */
public final class MainActivity extends Activity {
    @Override
    protected void onCreate(Bundle savedInstanceState) {
        super.onCreate(savedInstanceState);
        LinearLayout root = new LinearLayout(this);
        root.setOrientation(LinearLayout.VERTICAL);
        root.setPadding(24, 24, 24, 24);
        TextView intro = new TextView(this);
        intro.setText("Point the camera at a ceiling panel of the map. Set the server in Settings first.");
        root.addView(intro);
        root.addView(mode("Live position", LiveActivity.class));
        root.addView(mode("Align under the panel (test bench)", AlignmentActivity.class));
        root.addView(mode("Calibrate camera (ChArUco board)", CameraCalibrationActivity.class));
        root.addView(mode("Survey room (panel positions)", SurveyActivity.class));
        root.addView(mode("Test bench (391 cells)", BenchActivity.class));
        root.addView(mode("Settings", SettingsActivity.class));
        setContentView(root);
    }

    private Button mode(String label, final Class<? extends Activity> screen) {
        Button b = new Button(this);
        b.setText(label);
        b.setOnClickListener(new View.OnClickListener() {
            @Override
            public void onClick(View v) {
                startActivity(new Intent(MainActivity.this, screen));
            }
        });
        return b;
    }
}
