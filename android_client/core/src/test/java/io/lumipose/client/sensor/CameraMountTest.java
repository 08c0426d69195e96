package io.lumipose.client.sensor;

import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertThrows;

import org.junit.jupiter.api.Test;

class CameraMountTest {
    @Test
    void everyMountIsAProperRotation() {
        for (LensFacing f : LensFacing.values()) {
            for (int o = 0; o < 360; o += 90) {
                double[][] m = CameraMount.cameraFromDevice(o, f);
                for (int i = 0; i < 3; i++) {
                    for (int j = 0; j < 3; j++) {
                        double dot = m[i][0] * m[j][0] + m[i][1] * m[j][1] + m[i][2] * m[j][2];
                        assertEquals(i == j ? 1.0 : 0.0, dot, 1e-12, f + " " + o);
                    }
                }
                double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
                        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
                        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
                assertEquals(1.0, det, 1e-12, "right-handed " + f + " " + o);
            }
        }
    }

    @Test
    void opticalAxisLooksOutOfTheRightSide() {
        assertEquals(-1.0, CameraMount.cameraFromDevice(90, LensFacing.BACK)[2][2], 0);
        assertEquals(1.0, CameraMount.cameraFromDevice(270, LensFacing.FRONT)[2][2], 0);
        assertThrows(IllegalArgumentException.class, () -> CameraMount.cameraFromDevice(90, null));
    }
}
