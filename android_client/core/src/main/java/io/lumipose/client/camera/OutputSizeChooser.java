package io.lumipose.client.camera;

import java.util.List;

/** Picks the YUV_420_888 output size: the largest one within a pixel budget that keeps the sensor's aspect. */
public final class OutputSizeChooser {
    private OutputSizeChooser() {
    }

    /**
     * @param offered   sizes the stream configuration offers
     * @param sensor    the active array (its aspect is the uncropped field of view)
     * @param maxPixels upper bound on width * height (upload size and server time grow with it)
     */
    public static PixelSize choose(List<PixelSize> offered, ArrayRect sensor, long maxPixels) {
        if (offered == null || offered.isEmpty()) {
            throw new IllegalArgumentException("the camera offers no YUV_420_888 output size");
        }
        double sensorAspect = (double) sensor.width / sensor.height;
        PixelSize bestSameAspect = null;
        PixelSize bestAny = null;
        for (PixelSize s : offered) {
            if (s.pixels() > maxPixels) {
                continue;
            }
            boolean sameAspect = Math.abs((double) s.width / s.height - sensorAspect) < 0.01 * sensorAspect;
            if (sameAspect && (bestSameAspect == null || s.pixels() > bestSameAspect.pixels())) {
                bestSameAspect = s;
            }
            if (bestAny == null || s.pixels() > bestAny.pixels()) {
                bestAny = s;
            }
        }
        if (bestSameAspect != null) {
            return bestSameAspect;
        }
        if (bestAny != null) {
            return bestAny;
        }
        throw new IllegalArgumentException("no YUV_420_888 output size within " + maxPixels + " pixels");
    }
}
