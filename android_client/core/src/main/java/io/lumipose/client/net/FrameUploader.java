package io.lumipose.client.net;

import io.lumipose.client.frame.FrameMeta;

/** Sends one frame and returns the server's answer; {@link LumiposeClient} is the real one. */
public interface FrameUploader {
    LocateResult upload(byte[] luma, FrameMeta meta) throws Exception;
}
