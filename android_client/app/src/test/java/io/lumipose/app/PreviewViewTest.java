package io.lumipose.app;

import static org.junit.Assert.assertNotSame;
import static org.junit.Assert.assertSame;

import android.graphics.Bitmap;

import java.nio.ByteBuffer;

import org.junit.Test;
import org.junit.runner.RunWith;
import org.robolectric.RobolectricTestRunner;
import org.robolectric.RuntimeEnvironment;
import org.robolectric.annotation.GraphicsMode;

import io.lumipose.client.frame.GreyPreview;

/** The preview keeps one bitmap while the picture keeps its size (it was a new one five times a second). */
@RunWith(RobolectricTestRunner.class)
@GraphicsMode(GraphicsMode.Mode.NATIVE)
public class PreviewViewTest {
    private static GreyPreview picture(int width, int height, int value) {
        byte[] luma = new byte[width * height];
        java.util.Arrays.fill(luma, (byte) value);
        return GreyPreview.of(ByteBuffer.wrap(luma), width, height, width, 1, 64);
    }

    @Test
    public void reusesItsBitmapWhileTheSizeStays() {
        PreviewView view = new PreviewView(RuntimeEnvironment.getApplication());
        view.show(picture(320, 240, 10));
        Bitmap first = Screens.get(view, "bitmap");
        view.show(picture(320, 240, 200));
        assertSame(first, Screens.get(view, "bitmap"));
        view.show(picture(240, 320, 200));
        assertNotSame("a new size, a new bitmap", first, Screens.get(view, "bitmap"));
    }
}
