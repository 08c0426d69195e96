package io.lumipose.client.net;

import static org.junit.jupiter.api.Assertions.assertArrayEquals;
import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertNull;
import static org.junit.jupiter.api.Assertions.assertThrows;

import org.junit.jupiter.api.Test;

import io.lumipose.client.json.ContractException;

/** The result's position uncertainty (docs/contract.md, "Uncertainty"). */
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
}
