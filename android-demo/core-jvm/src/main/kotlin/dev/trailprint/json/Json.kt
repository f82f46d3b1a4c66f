package dev.trailprint.json

/**
 * A small JSON reader and writer for the robot protocol (rosbridge speaks JSON) without
 * pulling a serialization library into the demo.
 *
 * Values map to Kotlin as: object → `Map<String, Any?>` (insertion order kept), array →
 * `List<Any?>`, string → `String`, number → `Double`, `true`/`false` → `Boolean`,
 * `null` → `null`. [encode] also accepts `Int`, `Long` and `Float`.
 */
object Json {
    /** Parses one JSON value; throws [JsonException] with the offset of the problem. */
    fun parse(text: String): Any? {
        val p = Parser(text)
        p.ws()
        val v = p.value()
        p.ws()
        if (p.i != text.length) p.fail("unexpected ${text[p.i]} after the value")
        return v
    }

    /** The JSON text of [value] (no spaces). Non-finite numbers are an error. */
    fun encode(value: Any?): String = StringBuilder().also { write(it, value) }.toString()

    private fun write(out: StringBuilder, v: Any?) {
        when (v) {
            null -> out.append("null")
            is Boolean -> out.append(v)
            is Int, is Long, is Short, is Byte -> out.append(v)
            is Double -> writeDouble(out, v)
            is Float -> writeDouble(out, v.toDouble())
            is String -> writeString(out, v)
            is Map<*, *> -> writeItems(out, '{', '}', v.entries) { (k, x) ->
                writeString(out, k as? String ?: throw JsonException("object key $k is not a string"))
                out.append(':')
                write(out, x)
            }
            is Iterable<*> -> writeItems(out, '[', ']', v) { write(out, it) }
            is DoubleArray -> write(out, v.toList())
            else -> throw JsonException("cannot encode ${v::class.simpleName} as JSON")
        }
    }

    /** [items] between [open] and [close], separated by commas, each written by [item]. */
    private inline fun <T> writeItems(out: StringBuilder, open: Char, close: Char, items: Iterable<T>, item: (T) -> Unit) {
        out.append(open)
        var first = true
        for (x in items) {
            if (!first) out.append(',')
            first = false
            item(x)
        }
        out.append(close)
    }

    private fun writeDouble(out: StringBuilder, d: Double) {
        if (!d.isFinite()) throw JsonException("cannot encode the non-finite number $d as JSON")
        if (d == Math.rint(d) && kotlin.math.abs(d) < 1e15) out.append(d.toLong()).append(".0") else out.append(d)
    }

    private fun writeString(out: StringBuilder, s: String) {
        out.append('"')
        for (c in s) {
            when (c) {
                '"' -> out.append("\\\"")
                '\\' -> out.append("\\\\")
                '\n' -> out.append("\\n")
                '\r' -> out.append("\\r")
                '\t' -> out.append("\\t")
                '\b' -> out.append("\\b")
                '\u000c' -> out.append("\\f")
                else -> if (c < ' ') out.append(String.format("\\u%04x", c.code)) else out.append(c)
            }
        }
        out.append('"')
    }

    private class Parser(val s: String) {
        var i = 0

        fun fail(msg: String): Nothing = throw JsonException("JSON at offset $i: $msg")

        fun ws() {
            while (i < s.length && (s[i] == ' ' || s[i] == '\n' || s[i] == '\r' || s[i] == '\t')) i++
        }

        fun value(): Any? {
            if (i >= s.length) fail("unexpected end of text")
            return when (val c = s[i]) {
                '{' -> obj()
                '[' -> arr()
                '"' -> str()
                't' -> lit("true", true)
                'f' -> lit("false", false)
                'n' -> lit("null", null)
                else -> if (c == '-' || c in '0'..'9') num() else fail("unexpected $c")
            }
        }

        fun lit(word: String, v: Any?): Any? {
            if (!s.startsWith(word, i)) fail("expected $word")
            i += word.length
            return v
        }

        fun obj(): Map<String, Any?> {
            val m = LinkedHashMap<String, Any?>()
            items('}', "object") {
                if (i >= s.length || s[i] != '"') fail("expected a string key")
                val k = str()
                ws()
                if (i >= s.length || s[i] != ':') fail("expected :")
                i++
                ws()
                m[k] = value()
            }
            return m
        }

        fun arr(): List<Any?> {
            val l = ArrayList<Any?>()
            items(']', "array") { l.add(value()) }
            return l
        }

        /**
         * The comma-separated items of an [what] (object or array) whose opening bracket is
         * at [i], each read by [item], up to and past the [close] bracket.
         */
        inline fun items(close: Char, what: String, item: () -> Unit) {
            i++
            ws()
            if (i < s.length && s[i] == close) { i++; return }
            while (true) {
                ws()
                item()
                ws()
                if (i >= s.length) fail("unterminated $what")
                when (s[i]) {
                    ',' -> i++
                    close -> { i++; return }
                    else -> fail("expected , or $close")
                }
            }
        }

        fun str(): String {
            val b = StringBuilder()
            i++
            while (true) {
                if (i >= s.length) fail("unterminated string")
                val c = s[i++]
                when {
                    c == '"' -> return b.toString()
                    c == '\\' -> {
                        if (i >= s.length) fail("unterminated escape")
                        when (val e = s[i++]) {
                            '"' -> b.append('"'); '\\' -> b.append('\\'); '/' -> b.append('/')
                            'b' -> b.append('\b'); 'f' -> b.append('\u000c'); 'n' -> b.append('\n')
                            'r' -> b.append('\r'); 't' -> b.append('\t')
                            'u' -> {
                                if (i + 4 > s.length) fail("short \\u escape")
                                b.append(s.substring(i, i + 4).toIntOrNull(16)?.toChar() ?: fail("bad \\u escape"))
                                i += 4
                            }
                            else -> fail("bad escape \\$e")
                        }
                    }
                    c < ' ' -> fail("control character in string")
                    else -> b.append(c)
                }
            }
        }

        fun num(): Double {
            val start = i
            if (s[i] == '-') i++
            while (i < s.length && (s[i].isDigit() || s[i] in ".eE+-")) i++
            return s.substring(start, i).toDoubleOrNull() ?: run { i = start; fail("bad number") }
        }
    }
}

/** Malformed JSON, or a value that JSON cannot carry. */
class JsonException(message: String) : RuntimeException(message)

/** Typed access into parsed JSON: `obj.path("pose", "pose", "position")`. */
@Suppress("UNCHECKED_CAST")
fun Any?.path(vararg keys: String): Any? {
    var cur = this
    for (k in keys) cur = (cur as? Map<String, Any?>)?.get(k) ?: return null
    return cur
}

/** The number at [keys], or null. */
fun Any?.double(vararg keys: String): Double? = path(*keys) as? Double
