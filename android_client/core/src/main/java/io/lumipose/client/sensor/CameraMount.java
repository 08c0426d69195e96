package io.lumipose.client.sensor;

/**
 * How the camera sits in the phone: the camera frame's axes (OpenCV: x right, y down, z forward,
 * of the image as Camera2 delivers it) written in Android's device frame (x right, y up, z out of
 * the screen, phone in its natural orientation).
 *
 * <p>First the upright image (the delivered one turned clockwise by {@code SENSOR_ORIENTATION} for
 * display): a back lens sees (x, -y, -z) of the device; a front lens, whose unmirrored image swaps
 * left and right, sees (-x, -y, z). The delivered image is that one turned back: its x axis is the
 * upright (cos t, sin t) direction and its y axis the upright (-sin t, cos t) direction (image
 * coordinates, y down).
 */
public final class CameraMount {
    private CameraMount() {
    }

    /**
     * @return 3x3 rows = camera x, y, z axes in device coordinates (a rotation: v_camera = M v_device)
     */
    public static double[][] cameraFromDevice(int sensorOrientationDeg, LensFacing facing) {
        if (sensorOrientationDeg % 90 != 0 || sensorOrientationDeg < 0 || sensorOrientationDeg >= 360) {
            throw new IllegalArgumentException("SENSOR_ORIENTATION must be 0, 90, 180 or 270, got " + sensorOrientationDeg);
        }
        if (facing == null) {
            throw new IllegalArgumentException("lens facing must be FRONT or BACK");
        }
        double[] ux = facing == LensFacing.FRONT ? new double[] {-1, 0, 0} : new double[] {1, 0, 0};
        double[] uy = {0, -1, 0};
        double[] uz = facing == LensFacing.FRONT ? new double[] {0, 0, 1} : new double[] {0, 0, -1};
        double t = Math.toRadians(sensorOrientationDeg);
        // Exact quarter turns: no 6e-17 residues in the sent JSON.
        double c = Math.rint(Math.cos(t));
        double s = Math.rint(Math.sin(t));
        double[][] m = new double[3][3];
        for (int i = 0; i < 3; i++) {
            m[0][i] = c * ux[i] + s * uy[i];
            m[1][i] = -s * ux[i] + c * uy[i];
            m[2][i] = uz[i];
        }
        return m;
    }

    /** A vector of the device frame (gravity, a rotation rate) in the camera frame. */
    public static double[] deviceToCamera(double[] vDevice, int sensorOrientationDeg, LensFacing facing) {
        return apply(cameraFromDevice(sensorOrientationDeg, facing), vDevice);
    }

    /** The inverse of {@link #deviceToCamera}: the mount is a rotation, its transpose turns back. */
    public static double[] cameraToDevice(double[] vCamera, int sensorOrientationDeg, LensFacing facing) {
        double[][] m = cameraFromDevice(sensorOrientationDeg, facing);
        double[] out = new double[3];
        for (int i = 0; i < 3; i++) {
            out[i] = m[0][i] * vCamera[0] + m[1][i] * vCamera[1] + m[2][i] * vCamera[2];
        }
        return out;
    }

    private static double[] apply(double[][] m, double[] v) {
        return new double[] {
            m[0][0] * v[0] + m[0][1] * v[1] + m[0][2] * v[2],
            m[1][0] * v[0] + m[1][1] * v[1] + m[1][2] * v[2],
            m[2][0] * v[0] + m[2][1] * v[1] + m[2][2] * v[2],
        };
    }
}
