package dev.trailprint.files

import dev.trailprint.Trailprint
import java.io.File
import kotlinx.coroutines.CoroutineDispatcher
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.withContext

/**
 * A file ready to leave the phone: on Android it is shared as a `FileProvider` content
 * URI (`ACTION_SEND` with `EXTRA_STREAM`), never as text in the intent, which would not
 * fit through Binder's ~1 MB transaction limit once a survey is an hour long.
 */
data class ShareableFile(val file: File, val mimeType: String, val title: String)

/**
 * Writes what the app shares — a session's fingerprints as CSV or JSON, a building's
 * survey bundle — as files in [dir] (on Android `cacheDir/exports`, the folder the
 * FileProvider serves). Each file is written atomically ([writeFileAtomically]); writing
 * the same export again replaces the file.
 */
class ExportFiles(
    val dir: File,
    private val api: Trailprint,
    private val io: CoroutineDispatcher = Dispatchers.IO,
) {
    /** The fingerprints of session [sessionId] as CSV (one column per access point). */
    suspend fun sessionCsv(sessionId: Long): ShareableFile = withContext(io) {
        api.store.resumeSession(sessionId).use { s ->
            val name = buildingName(s.buildingId())
            write("trailprint-${slug(name)}-session-$sessionId.csv", s.exportCsv(), CSV, "Fingerprints of session $sessionId (CSV)")
        }
    }

    /** The fingerprints of session [sessionId] as the `trailprint export --collected` JSON. */
    suspend fun sessionJson(sessionId: Long): ShareableFile = withContext(io) {
        api.store.resumeSession(sessionId).use { s ->
            val name = buildingName(s.buildingId())
            write("trailprint-${slug(name)}-session-$sessionId.json", s.exportJson(), JSON, "Fingerprints of session $sessionId (JSON)")
        }
    }

    /**
     * The survey bundle of building [buildingId] (its sessions, with this [device]'s and
     * [surveyorName]'s provenance) for a coordinator to import.
     */
    suspend fun bundle(buildingId: Long, device: String?, surveyorName: String?): ShareableFile = withContext(io) {
        val name = buildingName(buildingId)
        val text = api.store.exportBundle(buildingId, device, surveyorName)
        val who = slug(surveyorName ?: device ?: "phone")
        write("trailprint-${slug(name)}-bundle-$who.json", text, JSON, "Survey bundle of $name")
    }

    /**
     * The bundle of just the sessions [sessionIds] (of one building), for re-sharing chosen
     * past surveys; named after the building, the sessions and [surveyorName] or [device].
     */
    suspend fun sessionsBundle(sessionIds: List<Long>, device: String?, surveyorName: String?): ShareableFile = withContext(io) {
        val text = api.store.exportSessionsBundle(sessionIds, device, surveyorName)
        val ids = sessionIds.distinct().sorted()
        val first = api.store.resumeSession(ids.first()).use { it.buildingId() }
        val name = buildingName(first)
        val who = slug(surveyorName ?: device ?: "phone")
        val which = if (ids.size == 1) "session-${ids[0]}" else "sessions-${ids.first()}-to-${ids.last()}-${ids.size}"
        write("trailprint-${slug(name)}-bundle-$which-$who.json", text, JSON, "Survey bundle of $name (${ids.size} session${if (ids.size == 1) "" else "s"})")
    }

    /** Writes [text] as [fileName] in [dir]. */
    fun write(fileName: String, text: String, mimeType: String, title: String): ShareableFile {
        val f = File(dir, fileName)
        writeFileAtomically(f, text)
        return ShareableFile(f, mimeType, title)
    }

    private fun buildingName(buildingId: Long): String =
        api.store.listBuildings().firstOrNull { it.id == buildingId }?.name ?: "building-$buildingId"

    companion object {
        const val CSV = "text/csv"
        const val JSON = "application/json"

        /** A file-name-safe form of [name]: lower case letters, digits and dashes, at most 40. */
        fun slug(name: String): String {
            val s = name.lowercase().replace(Regex("[^a-z0-9]+"), "-").trim('-').take(40).trim('-')
            return s.ifEmpty { "x" }
        }
    }
}
