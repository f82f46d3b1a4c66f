package dev.trailprint.survey

import dev.trailprint.AppException
import dev.trailprint.files.writeFileAtomically
import dev.trailprint.json.Json
import dev.trailprint.json.JsonException
import java.io.File
import java.io.IOException

/** Who walks the survey: a person with a phone, or a robot carrying one. */
enum class SurveyMode { HUMAN, ROBOT }

/**
 * The survey the app is running, as much as a restarted process needs to carry on: the
 * session (its events are in the database), the plan, the mode and the robot's address.
 */
data class ActiveSurvey(
    val sessionId: Long,
    val planId: Long,
    val mode: SurveyMode,
    /** Robot mode: the rosbridge WebSocket URL, or null for the simulated robot. */
    val rosbridgeUrl: String? = null,
    val startedMs: Long,
)

/** What the active-survey record says at launch, without throwing (see [ActiveSurveyFile.check]). */
sealed interface RecordCheck {
    /** No survey was running. */
    data object None : RecordCheck

    /** A survey was running: carry on with it. */
    data class Found(val survey: ActiveSurvey) : RecordCheck

    /** The record exists but cannot be read; [message] names the file and the field. */
    data class Unreadable(val message: String) : RecordCheck {
        /** What the surveyor reads above "Forget". */
        val prompt: String
            get() = "The survey that was running when Trailprint last stopped cannot be carried on: $message. " +
                "Forget it to survey again; what it collected stays in the database (Past surveys)."
    }
}

/**
 * Which survey is active, in one small JSON file (`trailprint-active/1`) next to the
 * database. Written atomically when a survey starts and deleted when it ends, so after
 * the process is killed the next one finds the session to resume. A file that does not
 * parse is an [AppException] naming the file and the field, never a silent "no survey".
 */
class ActiveSurveyFile(val file: File) {
    /** The active survey, or null when none is recorded. */
    fun read(): ActiveSurvey? {
        if (!file.exists()) return null
        val text = try {
            file.readText()
        } catch (e: IOException) {
            throw AppException("cannot read $file: ${e.message}", e)
        }
        val doc = try {
            Json.parse(text)
        } catch (e: JsonException) {
            throw AppException("$file: ${e.message}", e)
        }
        val o = doc as? Map<*, *> ?: throw AppException("$file: expected a JSON object")
        fun bad(field: String, what: String): Nothing = throw AppException("$file: field $field: $what, got ${runCatching { Json.encode(o[field]) }.getOrElse { o[field].toString() }}")
        if (o["format"] != FORMAT) bad("format", "expected \"$FORMAT\"")
        fun whole(field: String): Long {
            val d = o[field] as? Double ?: bad(field, "expected a number")
            if (d != Math.rint(d)) bad(field, "expected a whole number")
            return d.toLong()
        }
        val mode = when (o["mode"]) {
            "human" -> SurveyMode.HUMAN
            "robot" -> SurveyMode.ROBOT
            else -> bad("mode", "expected \"human\" or \"robot\"")
        }
        val url = o["rosbridge_url"]
        if (url != null && url !is String) bad("rosbridge_url", "expected a string or null")
        return ActiveSurvey(whole("session_id"), whole("plan_id"), mode, url as String?, whole("started_ms"))
    }

    /** [read], with an unreadable record as a value rather than an exception (the app's launch). */
    fun check(): RecordCheck = try {
        read()?.let { RecordCheck.Found(it) } ?: RecordCheck.None
    } catch (e: AppException) {
        RecordCheck.Unreadable(e.message ?: "cannot read $file")
    }

    /** Records [survey] as the active one (replacing any other). */
    fun write(survey: ActiveSurvey) = writeFileAtomically(
        file,
        Json.encode(
            linkedMapOf(
                "format" to FORMAT,
                "session_id" to survey.sessionId,
                "plan_id" to survey.planId,
                "mode" to survey.mode.name.lowercase(),
                "rosbridge_url" to survey.rosbridgeUrl,
                "started_ms" to survey.startedMs,
            ),
        ) + "\n",
    )

    /** No survey is active any more. */
    fun clear() {
        if (file.exists() && !file.delete()) throw AppException("cannot delete $file")
    }

    companion object {
        const val FORMAT = "trailprint-active/1"
    }
}
