package io.lumipose.client.camera;

import java.util.ArrayList;
import java.util.Arrays;
import java.util.List;

import org.json.JSONArray;
import org.json.JSONObject;

import io.lumipose.client.json.ContractException;
import io.lumipose.client.json.Json;

/** The shapes CameraFacts and FrameResult JSON share: rectangles, sizes, integer arrays, enum names. */
final class CameraJson {
    private CameraJson() {
    }

    /** [left, top, width, height] in pixel-array coordinates, or null. */
    static ArrayRect optRect(JSONObject o, String key) {
        long[] v = optLongs(o, key, 4);
        if (v == null) {
            return null;
        }
        if (v[2] <= 0 || v[3] <= 0) {
            throw new ContractException(key, "width and height must be > 0, got " + v[2] + "x" + v[3]);
        }
        return new ArrayRect((int) v[0], (int) v[1], (int) v[2], (int) v[3]);
    }

    static ArrayRect requireRect(JSONObject o, String key) {
        ArrayRect r = optRect(o, key);
        if (r == null) {
            throw new ContractException(key, "missing");
        }
        return r;
    }

    static JSONArray rect(ArrayRect r) {
        if (r == null) {
            return null;
        }
        return ints(new long[] {r.left, r.top, r.width, r.height});
    }

    /** An array of integers that fit an int; {@code length} < 0 accepts any length. */
    static long[] optLongs(JSONObject o, String key, int length) {
        double[] d = Json.optDoubles(o, key, key, length);
        if (d == null) {
            return null;
        }
        long[] out = new long[d.length];
        for (int i = 0; i < d.length; i++) {
            if (d[i] != Math.rint(d[i]) || Math.abs(d[i]) > Long.MAX_VALUE / 2) {
                throw new ContractException(key + "[" + i + "]", "must be an integer, got " + d[i]);
            }
            out[i] = (long) d[i];
        }
        return out;
    }

    static JSONArray ints(long[] values) {
        JSONArray a = new JSONArray();
        for (long v : values) {
            a.put(v);
        }
        return a;
    }

    static JSONArray doubles(double[] values) {
        return values == null ? null : Json.array(values);
    }

    /** A lower-case enum name that must be one of {@code allowed}; null when absent. */
    static String optChoice(JSONObject o, String key, String... allowed) {
        String v = Json.optString(o, key, key);
        if (v != null && !Arrays.asList(allowed).contains(v)) {
            throw new ContractException(key, "must be one of " + Arrays.toString(allowed) + ", got '" + v + "'");
        }
        return v;
    }

    /** A list of names; null when absent (the device does not report the key). */
    static List<String> optNames(JSONObject o, String key) {
        if (!Json.isPresent(o, key)) {
            return null;
        }
        if (!(o.opt(key) instanceof JSONArray)) {
            throw new ContractException(key, "must be an array of strings");
        }
        JSONArray a = (JSONArray) o.opt(key);
        List<String> out = new ArrayList<String>();
        for (int i = 0; i < a.length(); i++) {
            if (!(a.opt(i) instanceof String)) {
                throw new ContractException(key + "[" + i + "]", "must be a string, got " + a.opt(i));
            }
            out.add((String) a.opt(i));
        }
        return out;
    }

    static JSONArray names(List<String> names) {
        if (names == null) {
            return null;
        }
        JSONArray a = new JSONArray();
        for (String n : names) {
            a.put(n);
        }
        return a;
    }

    static Integer optInt(JSONObject o, String key) {
        Long v = Json.optLong(o, key, key);
        if (v == null) {
            return null;
        }
        if (v > Integer.MAX_VALUE || v < Integer.MIN_VALUE) {
            throw new ContractException(key, "out of range: " + v);
        }
        return v.intValue();
    }

    static double[] copy(double[] v) {
        return v == null ? null : v.clone();
    }

    static List<String> copy(List<String> v) {
        return v == null ? null : java.util.Collections.unmodifiableList(new ArrayList<String>(v));
    }
}
