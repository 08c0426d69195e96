package io.lumipose.client.json;

import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertNull;
import static org.junit.jupiter.api.Assertions.assertThrows;

import java.util.Set;

import org.json.JSONObject;
import org.junit.jupiter.api.Test;

class JsonTest {
    @Test
    void asciiOnlyEscapesEverythingAboveAscii() {
        assertEquals("{\"d\":\"Cam\\u00e9ra \\u20ac\"}", Json.asciiOnly("{\"d\":\"Caméra €\"}"));
        assertEquals("Caméra €", new JSONObject(Json.asciiOnly("{\"d\":\"Caméra €\"}")).getString("d"));
    }

    @Test
    void typesAreCheckedAndTheFieldNamed() {
        JSONObject o = new JSONObject("{\"n\": 1.5, \"i\": 3, \"s\": \"x\", \"nul\": null, \"a\": [1, \"b\"]}");
        assertEquals("p.n", assertThrows(ContractException.class, () -> Json.optLong(o, "n", "p.n")).field);
        assertEquals(3L, Json.optLong(o, "i", "i"));
        assertEquals(3.0, Json.optDouble(o, "i", "i"));
        assertEquals("s", assertThrows(ContractException.class, () -> Json.optDouble(o, "s", "s")).field);
        assertNull(Json.optDouble(o, "nul", "nul"), "JSON null reads as absent");
        assertNull(Json.optString(o, "missing", "missing"));
        assertEquals("a[1]", assertThrows(ContractException.class, () -> Json.optDoubles(o, "a", "a", -1)).field);
        assertEquals("a", assertThrows(ContractException.class, () -> Json.optDoubles(o, "a", "a", 3)).field);
        assertEquals("i", assertThrows(ContractException.class, () -> Json.requireObject(o, "i", "i")).field);
    }

    @Test
    void extrasAreTheUnknownFields() {
        JSONObject o = new JSONObject("{\"known\": 1, \"other\": {\"x\": 2}}");
        JSONObject extras = Json.extras(o, Set.of("known"));
        assertEquals(Set.of("other"), extras.keySet());
        assertEquals(2, extras.getJSONObject("other").getInt("x"));
    }

    @Test
    void schemaMustMatchWhenGiven() {
        Json.checkSchema(new JSONObject("{}"), "lumipose.map/1");
        Json.checkSchema(new JSONObject("{\"schema\": \"lumipose.map/1\"}"), "lumipose.map/1");
        assertThrows(ContractException.class,
                () -> Json.checkSchema(new JSONObject("{\"schema\": \"lumipose.map/2\"}"), "lumipose.map/1"));
    }
}
