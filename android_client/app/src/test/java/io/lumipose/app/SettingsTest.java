package io.lumipose.app;

import static org.junit.Assert.assertEquals;
import static org.junit.Assert.assertNotEquals;

import android.view.View;
import android.widget.EditText;

import org.junit.Test;
import org.junit.runner.RunWith;
import org.robolectric.Robolectric;
import org.robolectric.RobolectricTestRunner;
import org.robolectric.android.controller.ActivityController;

/** Values typed but not saved yet survive the screen's recreation (rotation, dark mode, ...). */
@RunWith(RobolectricTestRunner.class)
public class SettingsTest {
    private static final String[] FIELDS = {"url", "key", "mapName", "handHeight", "megapixels", "idExposure",
        "bearing"};

    @Test
    public void typedValuesSurviveRecreation() {
        ActivityController<SettingsActivity> c = Robolectric.buildActivity(SettingsActivity.class).setup();
        for (int i = 0; i < FIELDS.length; i++) {
            EditText e = Screens.get(c.get(), FIELDS[i]);
            assertNotEquals(FIELDS[i] + " has no id: the framework cannot restore it", View.NO_ID, e.getId());
            e.setText("typed " + i);
        }
        c.recreate();
        for (int i = 0; i < FIELDS.length; i++) {
            EditText e = Screens.get(c.get(), FIELDS[i]);
            assertEquals(FIELDS[i], "typed " + i, e.getText().toString());
        }
    }
}
