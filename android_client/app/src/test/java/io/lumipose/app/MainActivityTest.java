package io.lumipose.app;

import static org.junit.Assert.assertEquals;

import org.junit.Test;
import org.junit.runner.RunWith;
import org.robolectric.Robolectric;
import org.robolectric.RobolectricTestRunner;
import org.robolectric.android.controller.ActivityController;

@RunWith(RobolectricTestRunner.class)
public class MainActivityTest {
    @Test
    public void startsAndSurvivesRecreate() {
        ActivityController<MainActivity> c = Robolectric.buildActivity(MainActivity.class).setup();
        c.recreate();
        assertEquals("Lumipose", c.get().getTitle().toString());
    }
}
