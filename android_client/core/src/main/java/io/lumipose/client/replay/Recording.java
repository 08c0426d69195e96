package io.lumipose.client.replay;

import java.io.File;
import java.io.IOException;
import java.nio.charset.Charset;
import java.nio.file.Files;
import java.util.ArrayList;
import java.util.Arrays;
import java.util.Collections;
import java.util.List;

import org.json.JSONObject;

import io.lumipose.client.json.Json;

/**
 * A folder written by {@code lumipose simulate}: fixtures NAME.y + NAME.json, sorted by name
 * (the capture order), and the scene's beacon map (map.json) when there is one.
 */
public final class Recording {
    private static final Charset UTF_8 = Charset.forName("UTF-8");
    public final File folder;
    private final List<RecordedFrame> frames;
    private final String mapJson;

    private Recording(File folder, List<RecordedFrame> frames, String mapJson) {
        this.folder = folder;
        this.frames = Collections.unmodifiableList(frames);
        this.mapJson = mapJson;
    }

    public static Recording open(File folder) throws IOException {
        File[] files = folder.listFiles();
        if (files == null) {
            throw new IOException("not a folder: " + folder);
        }
        Arrays.sort(files);
        List<RecordedFrame> frames = new ArrayList<RecordedFrame>();
        for (File f : files) {
            String fileName = f.getName();
            if (!fileName.endsWith(".json")) {
                continue;
            }
            String stem = fileName.substring(0, fileName.length() - ".json".length());
            File pixels = new File(folder, stem + ".y");
            if (pixels.isFile()) {
                frames.add(new RecordedFrame(stem, Json.parseObject(read(f), fileName), pixels));
            }
        }
        if (frames.isEmpty()) {
            throw new IOException("no fixtures (NAME.y + NAME.json) in " + folder);
        }
        File map = new File(folder, "map.json");
        return new Recording(folder, frames, map.isFile() ? read(map) : null);
    }

    private static String read(File f) throws IOException {
        return new String(Files.readAllBytes(f.toPath()), UTF_8);
    }

    /** In capture order. */
    public List<RecordedFrame> frames() {
        return frames;
    }

    /** The scene's beacon map (the contract's map JSON), or null when the folder has none. */
    public JSONObject map() {
        return mapJson == null ? null : Json.parseObject(mapJson, "map.json");
    }
}
