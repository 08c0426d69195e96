package io.lumipose.client.json;

import java.util.ArrayList;
import java.util.Iterator;
import java.util.List;
import java.util.Set;

import org.json.JSONArray;
import org.json.JSONException;
import org.json.JSONObject;

/**
 * The few org.json operations the client needs, written so they compile against both the
 * Maven Central org.json (unchecked JSONException) and Android's (checked JSONException), and
 * turn every type or presence problem into a {@link ContractException} naming the field.
 */
public final class Json {
    private Json() {
    }

    public static JSONObject parseObject(String text, String what) {
        try {
            return new JSONObject(text);
        } catch (JSONException e) {
            throw new ContractException(what, "not a JSON object (" + e.getMessage() + ")");
        }
    }

    /** An absent "schema" is accepted (the contract's default); another one is refused. */
    public static void checkSchema(JSONObject o, String expected) {
        String schema = optString(o, "schema", "schema");
        if (schema != null && !expected.equals(schema)) {
            throw new ContractException("schema", "must be '" + expected + "', got '" + schema + "'");
        }
    }

    public static void put(JSONObject o, String key, Object value) {
        try {
            o.put(key, value == null ? JSONObject.NULL : value);
        } catch (JSONException e) {
            throw new ContractException(key, "cannot be written (" + e.getMessage() + ")");
        }
    }

    public static JSONArray array(double[] values) {
        JSONArray a = new JSONArray();
        for (double v : values) {
            a.put(Double.valueOf(v));
        }
        return a;
    }

    public static JSONArray matrix(double[][] rows) {
        JSONArray a = new JSONArray();
        for (double[] row : rows) {
            a.put(array(row));
        }
        return a;
    }

    private static Object present(JSONObject o, String key) {
        Object v = o.opt(key);
        return v == null || v == JSONObject.NULL ? null : v;
    }

    public static boolean isPresent(JSONObject o, String key) {
        return present(o, key) != null;
    }

    public static JSONObject requireObject(JSONObject o, String key, String path) {
        Object v = present(o, key);
        if (!(v instanceof JSONObject)) {
            throw new ContractException(path, v == null ? "missing" : "must be an object");
        }
        return (JSONObject) v;
    }

    public static JSONObject optObject(JSONObject o, String key, String path) {
        Object v = present(o, key);
        if (v == null) {
            return null;
        }
        if (!(v instanceof JSONObject)) {
            throw new ContractException(path, "must be an object");
        }
        return (JSONObject) v;
    }

    public static Double optDouble(JSONObject o, String key, String path) {
        Object v = present(o, key);
        if (v == null) {
            return null;
        }
        if (!(v instanceof Number) || v instanceof Byte) {
            throw new ContractException(path, "must be a number, got " + v);
        }
        double d = ((Number) v).doubleValue();
        if (Double.isNaN(d) || Double.isInfinite(d)) {
            throw new ContractException(path, "must be finite, got " + d);
        }
        return d;
    }

    public static double requireDouble(JSONObject o, String key, String path) {
        Double d = optDouble(o, key, path);
        if (d == null) {
            throw new ContractException(path, "missing");
        }
        return d;
    }

    public static Long optLong(JSONObject o, String key, String path) {
        Object v = present(o, key);
        if (v == null) {
            return null;
        }
        if (!(v instanceof Integer || v instanceof Long || v instanceof java.math.BigInteger)) {
            throw new ContractException(path, "must be an integer, got " + v);
        }
        if (v instanceof java.math.BigInteger && ((java.math.BigInteger) v).bitLength() > 63) {
            throw new ContractException(path, "out of range: " + v); // longValue() would keep only the low bits
        }
        return ((Number) v).longValue();
    }

    public static int requireInt(JSONObject o, String key, String path) {
        Long v = optLong(o, key, path);
        if (v == null) {
            throw new ContractException(path, "missing");
        }
        if (v > Integer.MAX_VALUE || v < Integer.MIN_VALUE) {
            throw new ContractException(path, "out of range: " + v);
        }
        return v.intValue();
    }

    public static String optString(JSONObject o, String key, String path) {
        Object v = present(o, key);
        if (v == null) {
            return null;
        }
        if (!(v instanceof String)) {
            throw new ContractException(path, "must be a string, got " + v);
        }
        return (String) v;
    }

    public static Boolean optBoolean(JSONObject o, String key, String path) {
        Object v = present(o, key);
        if (v == null) {
            return null;
        }
        if (!(v instanceof Boolean)) {
            throw new ContractException(path, "must be true or false, got " + v);
        }
        return (Boolean) v;
    }

    /** A number array; {@code length} < 0 accepts any length. Null when absent. */
    public static double[] optDoubles(JSONObject o, String key, String path, int length) {
        Object v = present(o, key);
        if (v == null) {
            return null;
        }
        return doubles(v, path, length);
    }

    private static double[] doubles(Object v, String path, int length) {
        if (!(v instanceof JSONArray)) {
            throw new ContractException(path, "must be an array of numbers");
        }
        JSONArray a = (JSONArray) v;
        if (length >= 0 && a.length() != length) {
            throw new ContractException(path, "must hold " + length + " numbers, got " + a.length());
        }
        double[] out = new double[a.length()];
        for (int i = 0; i < out.length; i++) {
            Object item = a.opt(i);
            if (!(item instanceof Number)) {
                throw new ContractException(path + "[" + i + "]", "must be a number, got " + item);
            }
            out[i] = ((Number) item).doubleValue();
            if (Double.isNaN(out[i]) || Double.isInfinite(out[i])) {
                throw new ContractException(path + "[" + i + "]", "must be finite");
            }
        }
        return out;
    }

    /** An array of number arrays, each of {@code innerLength}; null when absent. */
    public static double[][] optRows(JSONObject o, String key, String path, int rows, int innerLength) {
        Object v = present(o, key);
        if (v == null) {
            return null;
        }
        if (!(v instanceof JSONArray)) {
            throw new ContractException(path, "must be an array of arrays");
        }
        JSONArray a = (JSONArray) v;
        if (rows >= 0 && a.length() != rows) {
            throw new ContractException(path, "must hold " + rows + " rows, got " + a.length());
        }
        double[][] out = new double[a.length()][];
        for (int i = 0; i < out.length; i++) {
            out[i] = doubles(a.opt(i), path + "[" + i + "]", innerLength);
        }
        return out;
    }

    public static List<String> optStrings(JSONObject o, String key, String path) {
        List<String> out = new ArrayList<String>();
        Object v = present(o, key);
        if (v == null) {
            return out;
        }
        if (!(v instanceof JSONArray)) {
            throw new ContractException(path, "must be an array of strings");
        }
        JSONArray a = (JSONArray) v;
        for (int i = 0; i < a.length(); i++) {
            out.add(String.valueOf(a.opt(i)));
        }
        return out;
    }

    /** An array of objects; empty when absent. */
    public static List<JSONObject> optObjects(JSONObject o, String key, String path) {
        List<JSONObject> out = new ArrayList<JSONObject>();
        Object v = present(o, key);
        if (v == null) {
            return out;
        }
        if (!(v instanceof JSONArray)) {
            throw new ContractException(path, "must be an array of objects");
        }
        JSONArray a = (JSONArray) v;
        for (int i = 0; i < a.length(); i++) {
            if (!(a.opt(i) instanceof JSONObject)) {
                throw new ContractException(path + "[" + i + "]", "must be an object");
            }
            out.add((JSONObject) a.opt(i));
        }
        return out;
    }

    /** The fields of {@code o} not in {@code known}, as a new object. */
    public static JSONObject extras(JSONObject o, Set<String> known) {
        JSONObject out = new JSONObject();
        Iterator<String> keys = o.keys();
        while (keys.hasNext()) {
            String k = keys.next();
            if (!known.contains(k)) {
                put(out, k, o.opt(k));
            }
        }
        return out;
    }

    /** Copies every field of {@code from} into {@code to}. */
    public static void putAll(JSONObject to, JSONObject from) {
        Iterator<String> keys = from.keys();
        while (keys.hasNext()) {
            String k = keys.next();
            put(to, k, from.opt(k));
        }
    }

    /** JSON text with every non-ASCII character as a \\uXXXX escape, so it can travel in an HTTP header. */
    public static String asciiOnly(String json) {
        StringBuilder b = new StringBuilder(json.length());
        for (int i = 0; i < json.length(); i++) {
            char c = json.charAt(i);
            if (c < 0x80) {
                b.append(c);
            } else {
                b.append(String.format("\\u%04x", (int) c));
            }
        }
        return b.toString();
    }
}
