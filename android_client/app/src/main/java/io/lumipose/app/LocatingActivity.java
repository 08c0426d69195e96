package io.lumipose.app;

import io.lumipose.client.frame.FrameMeta;
import io.lumipose.client.net.LatestFrameUploader;

/** A camera screen that streams frames to POST /v1/locate: one in flight, the newest waiting frame wins. */
abstract class LocatingActivity extends CameraActivity implements LatestFrameUploader.Listener {
    private LatestFrameUploader uploader;

    @Override
    protected void onResume() {
        super.onResume();
        if (client != null) {
            uploader = new LatestFrameUploader(client, network, this);
        }
    }

    @Override
    protected void onPause() {
        if (uploader != null) {
            uploader.close();
            uploader = null;
        }
        super.onPause();
    }

    /** Whether this screen can use a frame now, besides the uploader being free. */
    protected boolean ready() {
        return true;
    }

    @Override
    public boolean wantFrame() {
        LatestFrameUploader u = uploader;
        return u != null && !u.busy() && ready();
    }

    @Override
    protected void handleFrame(byte[] luma, FrameMeta meta) {
        LatestFrameUploader u = uploader;
        if (u != null) {
            u.submit(luma, meta);
        }
    }

    @Override
    public void onFailure(FrameMeta meta, Exception error) {
        showStatus("Upload failed: " + error.getMessage());
    }
}
