package io.lumipose.client.net;

import static org.junit.jupiter.api.Assertions.assertArrayEquals;
import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertNull;
import static org.junit.jupiter.api.Assertions.assertThrows;
import static org.junit.jupiter.api.Assertions.assertTrue;

import org.junit.jupiter.api.Test;

import io.lumipose.client.json.ContractException;

/** The result's fields: its position uncertainty (docs/contract.md, "Uncertainty"), track, VLC reading, timings. */
class LocateResultTest {
    private static LocateResult withCovariance(String covariance) {
        return LocateResult.fromJson("{\"ok\": true, \"position_m\": [0, 0, 0], \"position_sigma_m\": [0, 0, 0], "
                + "\"position_covariance_m2\": " + covariance + "}");
    }

    @Test
    void theEllipseOfAnAxisAlignedCovarianceLiesAlongTheAxes() {
        double[] e = withCovariance("[[4e-6, 0, 0], [0, 1e-6, 0], [0, 0, 9e-6]]").errorEllipse95XyM();
        assertEquals(Math.sqrt(5.991 * 4e-6), e[0], 1e-15); // 2.448 sigma along X
        assertEquals(Math.sqrt(5.991 * 1e-6), e[1], 1e-15);
        assertEquals(0, e[2], 1e-12);
        double[] along = withCovariance("[[1e-6, 0, 0], [0, 4e-6, 0], [0, 0, 9e-6]]").errorEllipse95XyM();
        assertEquals(90, along[2], 1e-12, "major axis along Y");
        assertEquals(Math.sqrt(5.991 * 4e-6), along[0], 1e-15); // Z's variance plays no part
    }

    @Test
    void theEllipseOfATurnedCovarianceTurnsWithIt() {
        // Variances 4 and 1 (mm^2) along axes turned 30 degrees from X and Y.
        double c = Math.cos(Math.toRadians(30));
        double s = Math.sin(Math.toRadians(30));
        double xx = (4 * c * c + s * s) * 1e-6;
        double yy = (4 * s * s + c * c) * 1e-6;
        double xy = 3 * c * s * 1e-6;
        double[] e = withCovariance("[[" + xx + ", " + xy + ", 0], [" + xy + ", " + yy + ", 0], [0, 0, 1e-6]]")
                .errorEllipse95XyM();
        assertArrayEquals(new double[] {Math.sqrt(5.991 * 4e-6), Math.sqrt(5.991 * 1e-6), 30}, e, 1e-9);
    }

    @Test
    void aResultWithoutUncertaintyHasNone() {
        LocateResult r = LocateResult.fromJson("{\"ok\": true, \"position_m\": [0, 0, 0], "
                + "\"position_sigma_m\": null}");
        assertNull(r.positionSigmaM());
        assertNull(r.positionCovarianceM2());
        assertNull(r.errorEllipse95XyM());
    }

    @Test
    void aMalformedUncertaintyNamesTheField() {
        assertEquals("position_sigma_m", assertThrows(ContractException.class, () -> LocateResult.fromJson(
                "{\"ok\": true, \"position_m\": [0, 0, 0], \"position_sigma_m\": [1, 2]}")).field);
        assertEquals("position_covariance_m2[2]", assertThrows(ContractException.class,
                () -> withCovariance("[[1, 0, 0], [0, 1, 0], [0, 1]]")).field);
    }

    @Test
    void theAccessorsHandOutCopies() {
        LocateResult r = withCovariance("[[1, 0, 0], [0, 1, 0], [0, 0, 1]]");
        r.positionCovarianceM2()[0][0] = 5;
        r.positionSigmaM()[0] = 5;
        assertEquals(1, r.positionCovarianceM2()[0][0], 0);
        assertEquals(0, r.positionSigmaM()[0], 0);
    }

    @Test
    void theTrackTheVlcReadingAndTheTimingsAreRead() {
        LocateResult r = LocateResult.fromJson("{\"ok\": true, \"position_m\": [1, 2, 0], \"beacon_id\": 42, "
                + "\"beacon_id_source\": \"track\", \"beacons_in_view\": 2, \"ambiguity_ratio\": 0.25, "
                + "\"corners_px\": [[1, 2], [3, 4], [5, 6], [7, 8]], \"timing_ms\": {\"roi\": 1.5, \"total\": 4}, "
                + "\"vlc\": {\"beacon_id\": null, \"confidence\": 0.4, \"confident\": false, \"frames\": 3, "
                + "\"chips_seen\": 12.5, \"candidates\": 4}, "
                + "\"track\": {\"filtered_position_m\": [1.1, 2.1, 0], \"velocity_mps\": [0.5, 0, 0], "
                + "\"outlier\": true, \"beacon_id_carried\": true}}");
        assertEquals(2, r.beaconsInView().intValue());
        assertEquals(0.25, r.ambiguityRatio, 0);
        assertArrayEquals(new double[] {5, 6}, r.cornersPx()[2], 0);
        assertEquals(new java.util.HashSet<String>(java.util.Arrays.asList("roi", "total")), r.timingMs().keySet());
        assertEquals(4.0, r.timingMs().get("total"), 0);
        assertNull(r.vlc().beaconId);
        assertEquals(0.4, r.vlc().confidence, 0);
        assertEquals(3, r.vlc().frames);
        assertEquals(12.5, r.vlc().chipsSeen, 0);
        assertEquals(4, r.vlc().candidates);
        assertArrayEquals(new double[] {1.1, 2.1, 0}, r.track().filteredPositionM(), 0);
        assertArrayEquals(new double[] {0.5, 0, 0}, r.track().velocityMps(), 0);
        assertTrue(r.track().outlier && r.track().beaconIdCarried);
        r.cornersPx()[0][0] = 99;
        r.track().filteredPositionM()[0] = 99;
        assertEquals(1, r.cornersPx()[0][0], 0);
        assertEquals(1.1, r.track().filteredPositionM()[0], 0);
        assertThrows(UnsupportedOperationException.class, () -> r.timingMs().put("x", 1.0));
    }

    @Test
    void aResultWithoutTheOptionalBlocksHasNone() {
        LocateResult r = LocateResult.fromJson("{\"ok\": false, \"reason\": \"no_beacon\"}");
        assertNull(r.track());
        assertNull(r.vlc());
        assertNull(r.beaconsInView());
        assertNull(r.cornersPx());
        assertNull(r.ambiguityRatio);
        assertTrue(r.timingMs().isEmpty());
    }

    @Test
    void aMalformedTrackOrReadingNamesTheField() {
        assertEquals("track.outlier", assertThrows(ContractException.class, () -> LocateResult.fromJson(
                "{\"ok\": true, \"position_m\": [0, 0, 0], \"track\": {\"filtered_position_m\": [0, 0, 0], "
                        + "\"velocity_mps\": [0, 0, 0]}}")).field);
        assertEquals("vlc.frames", assertThrows(ContractException.class, () -> LocateResult.fromJson(
                "{\"ok\": true, \"position_m\": [0, 0, 0], \"vlc\": {\"confidence\": 1, \"confident\": true, "
                        + "\"chips_seen\": 3, \"candidates\": 1}}")).field);
        assertEquals("timing_ms.total", assertThrows(ContractException.class, () -> LocateResult.fromJson(
                "{\"ok\": true, \"position_m\": [0, 0, 0], \"timing_ms\": {\"total\": \"fast\"}}")).field);
    }
}
