package dev.trailprint.files

import dev.trailprint.team.WalkFiles
import java.io.InputStream
import java.nio.ByteBuffer
import java.nio.charset.CharacterCodingException
import java.nio.charset.CodingErrorAction
import kotlinx.coroutines.flow.MutableStateFlow

/** One file handed to the app (share sheet, "open with", a file picker), once classified. */
sealed interface Incoming {
    /** Its display name, for messages. */
    val name: String

    /** A coordinator's walk file (`trailprint-walk/1`): a plan to walk. */
    data class Walk(override val name: String, val text: String) : Incoming

    /** A survey bundle (`trailprint-bundle/1`) to import on the team screen. */
    data class Bundle(override val name: String, val text: String) : Incoming

    /** A building file (`survey-building/1`) to import on the buildings screen. */
    data class Building(override val name: String, val text: String) : Incoming

    /** Not something the app opens; [reason] says what it is and what would be. */
    data class Refused(override val name: String, val reason: String) : Incoming {
        fun line(): String = "$name: $reason"
    }
}

/**
 * Files handed to the app wait on such a flow for the screen that imports them: hands each
 * batch that arrives to [take] and empties the flow, so that a batch is taken once. Runs
 * until cancelled (with the screen's scope).
 */
suspend fun <T : Incoming> MutableStateFlow<List<T>>.takeEachBatch(take: suspend (List<T>) -> Unit): Nothing = collect { files ->
    if (files.isNotEmpty()) {
        value = emptyList()
        take(files)
    }
}

/** Where the app goes with a batch of incoming files. */
enum class Destination { WALK, TEAM, BUILDINGS, STAY }

/** The classified batch and what to do with it. */
data class IncomingRoute(
    val walks: List<Incoming.Walk>,
    val bundles: List<Incoming.Bundle>,
    val buildings: List<Incoming.Building>,
    val refused: List<Incoming.Refused>,
    val destination: Destination,
    /** What the surveyor reads (files refused, files kept for after the survey), or null. */
    val message: String?,
)

/**
 * Decides what a file shared to the app is, from its name, MIME type and bytes, so the
 * Android activity only reads the URI and hands them over: a walk file (a plan to walk),
 * a survey bundle (to import), a building file, or something else, refused with a
 * message naming the file and saying what it is.
 *
 * The kind is the top-level `"format"` field, found by a scan that skips nested values
 * without building the document (a two-hour survey's bundle is megabytes, and serde's
 * sorted keys put `"format"` after the body). Whether the rest is valid is for the
 * importer to say, with the field.
 */
object IncomingRouter {
    /** The largest file read: the core's bundle limit (`MAX_BUNDLE_BYTES`, 256 MiB). */
    const val MAX_BYTES: Long = 256L * 1024 * 1024

    private const val WHAT_OPENS = "Trailprint opens walk files (trailprint-walk/1), survey bundles (trailprint-bundle/1) and building files (survey-building/1)"

    /**
     * Reads at most [limit] bytes of [input]; null when there are more (the caller refuses
     * the file as too large without reading it all into memory).
     */
    fun readLimited(input: InputStream, limit: Long = MAX_BYTES): ByteArray? {
        val out = java.io.ByteArrayOutputStream()
        val buf = ByteArray(64 * 1024)
        var total = 0L
        while (true) {
            val n = input.read(buf)
            if (n < 0) return out.toByteArray()
            total += n
            if (total > limit) return null
            out.write(buf, 0, n)
        }
    }

    /** A file too large to read, refused by its size. */
    fun tooLarge(name: String, limit: Long = MAX_BYTES): Incoming.Refused =
        Incoming.Refused(name, "larger than ${limit / (1024 * 1024)} MiB, the most a bundle may be; not read")

    /** What the file [name] of type [mimeType] (null if unknown) holding [bytes] is. */
    fun classify(name: String, mimeType: String?, bytes: ByteArray): Incoming {
        val type = mimeType?.lowercase()?.substringBefore(';')?.trim()
        if (type != null && (type.startsWith("image/") || type.startsWith("video/") || type.startsWith("audio/"))) {
            return Incoming.Refused(name, "a file of type $type, not a Trailprint file. $WHAT_OPENS.")
        }
        if (bytes.isEmpty()) return Incoming.Refused(name, "the file is empty")
        val text = try {
            Charsets.UTF_8.newDecoder()
                .onMalformedInput(CodingErrorAction.REPORT)
                .onUnmappableCharacter(CodingErrorAction.REPORT)
                .decode(ByteBuffer.wrap(bytes)).toString()
                .removePrefix("\uFEFF")
        } catch (e: CharacterCodingException) {
            return Incoming.Refused(name, "not a text file (not UTF-8). $WHAT_OPENS.")
        }
        val first = text.firstOrNull { !it.isWhitespace() }
        if (first != '{') return Incoming.Refused(name, "not a JSON object (it starts with ${describe(first)}). $WHAT_OPENS.")
        return when (val format = topLevelFormat(text)) {
            WalkFiles.FORMAT -> Incoming.Walk(name, text)
            BUNDLE_FORMAT -> Incoming.Bundle(name, text)
            BUILDING_FORMAT -> Incoming.Building(name, text)
            null -> Incoming.Refused(name, "a JSON file without a top-level \"format\" field, not a Trailprint file. $WHAT_OPENS.")
            else -> Incoming.Refused(
                name,
                "format \"$format\" is not one this app reads. $WHAT_OPENS" +
                    if (format.startsWith("trailprint-")) " (is the app older than the phone that wrote it?)." else ".",
            )
        }
    }

    /**
     * Sorts a batch. Bundles take the app to the team screen, walk files (with no bundle)
     * to the walk screen, building files to the buildings screen. While a survey runs the
     * app stays on it ([Destination.STAY]): walk files wait in the inbox as "Not opened"
     * and bundles until the survey ends, and the message says so.
     */
    fun route(files: List<Incoming>, surveyRunning: Boolean = false): IncomingRoute {
        val walks = files.filterIsInstance<Incoming.Walk>()
        val bundles = files.filterIsInstance<Incoming.Bundle>()
        val buildings = files.filterIsInstance<Incoming.Building>()
        val refused = files.filterIsInstance<Incoming.Refused>()
        val usable = walks.size + bundles.size + buildings.size
        val destination = when {
            usable == 0 || surveyRunning -> Destination.STAY
            bundles.isNotEmpty() -> Destination.TEAM
            walks.isNotEmpty() -> Destination.WALK
            else -> Destination.BUILDINGS
        }
        val lines = buildList {
            refused.forEach { add("Not opened — ${it.line()}") }
            if (surveyRunning && usable > 0) {
                add("A survey is running: ${plural(usable, "received file")} wait until it ends (walk files under Walk files, \"Not opened\").")
            }
        }
        return IncomingRoute(walks, bundles, buildings, refused, destination, lines.joinToString("\n").ifEmpty { null })
    }

    private const val BUNDLE_FORMAT = "trailprint-bundle/1"
    private const val BUILDING_FORMAT = "survey-building/1"

    private fun plural(n: Int, what: String) = if (n == 1) "1 $what" else "$n ${what}s"

    private fun describe(c: Char?): String = when (c) {
        null -> "nothing but spaces"
        else -> "'$c'"
    }

    /**
     * The string value of the object's top-level `"format"` key, or null (no such key, or
     * not a string). Nested objects, arrays and strings are skipped in one pass.
     */
    fun topLevelFormat(text: String): String? {
        var i = text.indexOf('{')
        if (i < 0) return null
        i++
        var depth = 1
        var expectKey = true
        while (i < text.length && depth > 0) {
            val c = text[i]
            when {
                c == '"' -> {
                    val end = stringEnd(text, i) ?: return null
                    if (depth == 1 && expectKey) {
                        val key = text.substring(i + 1, end)
                        var j = end + 1
                        while (j < text.length && text[j].isWhitespace()) j++
                        if (j < text.length && text[j] == ':') {
                            j++
                            while (j < text.length && text[j].isWhitespace()) j++
                            if (key == "format") {
                                if (j >= text.length || text[j] != '"') return null
                                val vEnd = stringEnd(text, j) ?: return null
                                return unescape(text.substring(j + 1, vEnd))
                            }
                            expectKey = false
                            i = j
                            continue
                        }
                    }
                    i = end + 1
                    continue
                }
                c == '{' || c == '[' -> depth++
                c == '}' || c == ']' -> depth--
                c == ',' && depth == 1 -> expectKey = true
            }
            i++
        }
        return null
    }

    /** Index of the closing quote of the string opening at [start], or null if it never closes. */
    private fun stringEnd(text: String, start: Int): Int? {
        var j = start + 1
        while (j < text.length) {
            when (text[j]) {
                '\\' -> j += 2
                '"' -> return j
                else -> j++
            }
        }
        return null
    }

    private fun unescape(s: String): String = if ('\\' !in s) s else try {
        dev.trailprint.json.Json.parse("\"$s\"") as String
    } catch (e: Exception) {
        s
    }
}
