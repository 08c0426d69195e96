package io.lumipose.app;

import static org.junit.Assert.assertTrue;

import android.app.Activity;
import android.graphics.Bitmap;
import android.graphics.Canvas;
import android.view.View;

import java.io.File;
import java.io.FileOutputStream;
import java.io.IOException;
import java.io.OutputStream;
import java.util.HashSet;
import java.util.Set;

/**
 * A screen as Android's own drawing code renders it (the test class runs in Robolectric's native
 * graphics mode), saved as a PNG: under target/screenshots, or the folder of the system property
 * {@code lumipose.screenshots} (docs/android.md regenerates its pictures that way).
 */
final class Screenshots {
    private Screenshots() {
    }

    /** Draws the screen's window into {@code name}.png and checks it shows more than a blank page. */
    static File save(Activity screen, String name) throws IOException {
        View window = screen.getWindow().getDecorView();
        Bitmap picture = Bitmap.createBitmap(window.getWidth(), window.getHeight(), Bitmap.Config.ARGB_8888);
        window.draw(new Canvas(picture));
        Set<Integer> colours = new HashSet<Integer>();
        for (int y = 0; y < picture.getHeight(); y += 3) {
            for (int x = 0; x < picture.getWidth(); x += 3) {
                colours.add(picture.getPixel(x, y));
            }
        }
        assertTrue(name + ": the screen drew " + colours.size() + " colours: nothing on it?", colours.size() > 20);
        File folder = new File(System.getProperty("lumipose.screenshots", "target/screenshots"));
        if (!folder.isDirectory() && !folder.mkdirs()) {
            throw new IOException("cannot make " + folder);
        }
        File file = new File(folder, name + ".png");
        try (OutputStream out = new FileOutputStream(file)) {
            if (!picture.compress(Bitmap.CompressFormat.PNG, 100, out)) {
                throw new IOException("PNG not written: " + file);
            }
        }
        System.out.println("screenshot: " + file.getAbsolutePath() + " (" + picture.getWidth() + "x"
                + picture.getHeight() + ")");
        return file;
    }
}
