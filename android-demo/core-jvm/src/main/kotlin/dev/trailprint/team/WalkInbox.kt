package dev.trailprint.team

import dev.trailprint.AppException
import dev.trailprint.files.writeFileAtomically
import dev.trailprint.json.Json
import dev.trailprint.json.JsonException
import java.io.File
import java.security.MessageDigest

/** A walk file kept on the surveyor's phone, opened or not yet. */
data class InboxEntry(
    /** Stable: the same file received twice is the same entry. */
    val id: String,
    /** The file's name as it arrived. */
    val name: String,
    val receivedMs: Long,
    val assignment: WalkAssignment,
    /** The plan it was opened as, or null while "Not opened". */
    val openedPlanId: Long?,
) {
    val opened: Boolean get() = openedPlanId != null

    /** The line of the list: which walk, for whom, where, and whether it was opened. */
    fun line(): String {
        val a = assignment
        val who = a.surveyorName?.let { " for $it" } ?: ""
        val status = openedPlanId?.let { "Opened (plan $it)" } ?: "Not opened"
        return "Walk ${a.member} of ${a.members}$who · ${a.building} · %.0f m · $status".format(a.lengthM)
    }
}

/**
 * The walk files a surveyor's phone has received, kept in [dir] until they are opened as
 * plans: a walk file may arrive while a survey runs, or be shared while the surveyor is
 * busy, and must not be lost or imported behind their back. Each entry is the file's text
 * (`<id>.json`) and a small record (`<id>.meta.json`: name, time received, the plan it
 * was opened as), both written atomically. A file that is not a valid walk file is
 * refused on [add] (the error names the field) and nothing is kept.
 */
class WalkInbox(val dir: File, private val clock: () -> Long = System::currentTimeMillis) {
    /** Keeps the walk file [text] (named [name]); receiving the same file again keeps its status. */
    fun add(name: String, text: String): InboxEntry {
        val (assignment, _) = WalkFiles.decode(text, name)
        val id = idOf(text)
        entry(id)?.let { return it }
        writeFileAtomically(File(dir, "$id.json"), text)
        writeMeta(id, name, clock(), null)
        return InboxEntry(id, name, clock(), assignment, null)
    }

    /** Every kept walk file, the ones not opened first, then newest first. */
    fun entries(): List<InboxEntry> {
        val ids = dir.listFiles { f -> f.name.endsWith(".meta.json") }.orEmpty().map { it.name.removeSuffix(".meta.json") }
        return ids.mapNotNull(::entry).sortedWith(compareBy<InboxEntry> { it.opened }.thenByDescending { it.receivedMs })
    }

    /** The walks still "Not opened". */
    fun notOpened(): List<InboxEntry> = entries().filter { !it.opened }

    /** The text of entry [id] (to open it). */
    fun text(id: String): String = File(dir, "$id.json").let { f ->
        if (!f.exists()) throw AppException("walk file $id is no longer kept ($f)")
        f.readText()
    }

    /** Records that entry [id] was opened as plan [planId]. */
    fun markOpened(id: String, planId: Long): InboxEntry {
        val e = entry(id) ?: throw AppException("walk file $id is no longer kept in $dir")
        writeMeta(id, e.name, e.receivedMs, planId)
        return e.copy(openedPlanId = planId)
    }

    /** Deletes entry [id]. */
    fun remove(id: String) {
        listOf(File(dir, "$id.json"), File(dir, "$id.meta.json")).forEach { f ->
            if (f.exists() && !f.delete()) throw AppException("cannot delete $f")
        }
    }

    private fun entry(id: String): InboxEntry? {
        val meta = File(dir, "$id.meta.json")
        val body = File(dir, "$id.json")
        if (!meta.exists() || !body.exists()) return null
        val m = try {
            Json.parse(meta.readText()) as? Map<*, *>
        } catch (e: JsonException) {
            null
        } ?: throw AppException("$meta: expected a JSON object")
        val name = m["name"] as? String ?: throw AppException("$meta: field name: expected a string")
        val received = (m["received_ms"] as? Double)?.toLong() ?: throw AppException("$meta: field received_ms: expected a number")
        val plan = m["opened_plan_id"]?.let { (it as? Double)?.toLong() ?: throw AppException("$meta: field opened_plan_id: expected a number or null") }
        val (assignment, _) = WalkFiles.decode(body.readText(), name)
        return InboxEntry(id, name, received, assignment, plan)
    }

    private fun writeMeta(id: String, name: String, receivedMs: Long, planId: Long?) = writeFileAtomically(
        File(dir, "$id.meta.json"),
        Json.encode(linkedMapOf("format" to FORMAT, "name" to name, "received_ms" to receivedMs, "opened_plan_id" to planId)) + "\n",
    )

    companion object {
        const val FORMAT = "trailprint-inbox/1"

        /** The first 16 hex digits of the text's SHA-256. */
        fun idOf(text: String): String =
            MessageDigest.getInstance("SHA-256").digest(text.toByteArray()).take(8).joinToString("") { "%02x".format(it) }
    }
}
