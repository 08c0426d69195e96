package io.lumipose.client.camera;

import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertThrows;

import java.util.Arrays;
import java.util.Collections;
import java.util.List;

import org.junit.jupiter.api.Test;

class OutputSizeChooserTest {
    private static final List<PixelSize> OFFERED = Arrays.asList(new PixelSize(4032, 3024), new PixelSize(1920, 1080),
            new PixelSize(1600, 1200), new PixelSize(1280, 960), new PixelSize(640, 480));

    @Test
    void largestSameAspectWithinBudget() {
        assertEquals(new PixelSize(1600, 1200),
                OutputSizeChooser.choose(OFFERED, ArrayRect.ofSize(4032, 3024), 2_100_000));
        assertEquals(new PixelSize(4032, 3024),
                OutputSizeChooser.choose(OFFERED, ArrayRect.ofSize(4032, 3024), 13_000_000));
    }

    @Test
    void otherAspectOnlyWhenNoSameAspectFits() {
        List<PixelSize> wideOnly = Arrays.asList(new PixelSize(1920, 1080), new PixelSize(1280, 720));
        assertEquals(new PixelSize(1920, 1080),
                OutputSizeChooser.choose(wideOnly, ArrayRect.ofSize(4000, 3000), 2_100_000));
        assertThrows(IllegalArgumentException.class,
                () -> OutputSizeChooser.choose(wideOnly, ArrayRect.ofSize(4000, 3000), 1000));
        assertThrows(IllegalArgumentException.class,
                () -> OutputSizeChooser.choose(Collections.<PixelSize>emptyList(), ArrayRect.ofSize(4, 3), 1000));
    }
}
