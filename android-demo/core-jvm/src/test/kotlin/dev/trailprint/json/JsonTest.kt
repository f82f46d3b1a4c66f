package dev.trailprint.json

import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith
import kotlin.test.assertTrue

class JsonTest {
    @Test
    fun roundTripsNestedValues() {
        val v = mapOf("op" to "publish", "n" to listOf(1.5, -2.0, 3e-7), "ok" to true, "none" to null, "s" to "a\"b\\c\n\u0001é")
        val text = Json.encode(v)
        assertEquals(v, Json.parse(text))
        assertTrue("\\u0001" in text, text)
    }

    @Test
    fun parsesWhitespaceEscapesAndNumbers() {
        val v = Json.parse(" { \"a\" : [ 1 , 2.5e2 , -0.5 ] , \"u\" : \"\\u00e9\\/\" } ")
        assertEquals(listOf(1.0, 250.0, -0.5), v.path("a"))
        assertEquals("é/", v.path("u"))
        assertEquals(250.0, (v.path("a") as List<*>)[1])
    }

    @Test
    fun integralDoublesKeepADecimalPointAndIntsDoNot() {
        assertEquals("[2.0,2,-3.25]", Json.encode(listOf(2.0, 2, -3.25)))
    }

    @Test
    fun malformedTextNamesTheOffset() {
        val e = assertFailsWith<JsonException> { Json.parse("{\"a\": tru}") }
        assertTrue("offset 6" in e.message!!, e.message)
        assertFailsWith<JsonException> { Json.parse("[1, 2") }
        assertFailsWith<JsonException> { Json.parse("{} x") }
        assertFailsWith<JsonException> { Json.encode(Double.NaN) }
    }
}
