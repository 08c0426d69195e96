package io.lumipose.client.frame;

import io.lumipose.client.camera.Intrinsics;
import io.lumipose.client.sensor.GravityTransform;
import io.lumipose.client.sensor.HeadingEstimator;
import io.lumipose.client.sensor.LensFacing;

/**
 * Puts one captured frame's JSON together from the camera's fixed facts, the values the capture
 * result reports and the latest gravity reading. One instance per opened camera and output size.
 */
public final class FrameAssembler {
    private final int width;
    private final int height;
    private final Intrinsics intrinsics;
    private final int sensorOrientationDeg;
    private final LensFacing facing;
    private final Double mapXBearingDeg;

    /** @param facing null for an external camera, whose attitude to the phone is unknown: no gravity is sent */
    public FrameAssembler(int width, int height, Intrinsics intrinsics, int sensorOrientationDeg, LensFacing facing) {
        this(width, height, intrinsics, sensorOrientationDeg, facing, null);
    }

    /**
     * @param mapXBearingDeg compass bearing of the map's +X axis (deg clockwise from north), or null
     *                       to send no heading (the server then assumes |yaw| < 45 deg to the panel)
     */
    public FrameAssembler(int width, int height, Intrinsics intrinsics, int sensorOrientationDeg, LensFacing facing,
                          Double mapXBearingDeg) {
        if (width <= 0 || height <= 0) {
            throw new IllegalArgumentException("output size must be positive, got " + width + "x" + height);
        }
        this.width = width;
        this.height = height;
        this.intrinsics = intrinsics;
        this.sensorOrientationDeg = sensorOrientationDeg;
        this.facing = facing;
        this.mapXBearingDeg = mapXBearingDeg;
    }

    /**
     * @param values        per-frame values from the capture result (fields may be null)
     * @param gravityDevice TYPE_GRAVITY [x, y, z] m/s^2 at capture time, or null if none yet
     * @return the frame JSON for a packed Y8 buffer (row_stride = width, see {@link LumaPlane})
     */
    public FrameMeta assemble(CaptureValues values, float[] gravityDevice) {
        return assemble(values, gravityDevice, null);
    }

    /**
     * @param deviceToEnu row-major device-to-East-North-Up rotation from the rotation-vector sensor at
     *                    capture time, or null; used only with a map bearing
     */
    public FrameMeta assemble(CaptureValues values, float[] gravityDevice, float[] deviceToEnu) {
        FrameMeta.Builder b = FrameMeta.builder(width, height).rowStride(width).camera(intrinsics);
        if (values.exposureNs != null) {
            b.exposureS(values.exposureNs / 1e9);
        }
        if (values.sensitivityIso != null) {
            b.iso((double) values.sensitivityIso);
        }
        if (values.rollingShutterSkewNs != null) {
            b.rollingShutterSkewS(values.rollingShutterSkewNs / 1e9);
        }
        b.timestampNs(values.timestampNs);
        if (values.idFrame) {
            // The server reads an ID frame's stripes; it needs the exposure, skew and timestamp.
            b.frameKind("id");
        }
        if (gravityDevice != null && facing != null) {
            b.gravityCamera(GravityTransform.deviceToCamera(gravityDevice, sensorOrientationDeg, facing));
        }
        if (deviceToEnu != null && facing != null && mapXBearingDeg != null) {
            b.headingDeg(HeadingEstimator.cameraYawDeg(deviceToEnu, sensorOrientationDeg, facing, mapXBearingDeg));
        }
        return b.build();
    }
}
