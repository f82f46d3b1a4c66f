package dev.trailprint.ui

import dev.trailprint.AppException
import dev.trailprint.Trailprint
import dev.trailprint.ffi.SessionStatus
import dev.trailprint.files.ExportFiles
import dev.trailprint.files.ShareableFile
import dev.trailprint.runBusy
import java.time.Instant
import java.time.ZoneId
import java.time.format.DateTimeFormatter
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asStateFlow
import kotlinx.coroutines.flow.update
import kotlinx.coroutines.launch

/** A survey that has ended, as the list shows it. */
data class PastSurvey(
    val sessionId: Long,
    val buildingId: Long,
    val building: String,
    val createdMs: Long,
    val status: SessionStatus,
    val fingerprints: Long,
) {
    fun line(zone: ZoneId = ZoneId.systemDefault()): String {
        val day = DateTimeFormatter.ofPattern("yyyy-MM-dd HH:mm").withZone(zone).format(Instant.ofEpochMilli(createdMs))
        val how = if (status == SessionStatus.ABORTED) " (stopped early)" else ""
        return "$building · session $sessionId · $day · $fingerprints fingerprints$how"
    }
}

data class PastSurveysState(
    /** Newest first. */
    val surveys: List<PastSurvey> = emptyList(),
    /** Sessions ticked for one bundle. */
    val selected: Set<Long> = emptySet(),
    val busy: Boolean = false,
    /** The files to share now (several bundles when the ticked sessions span buildings). */
    val share: List<ShareableFile> = emptyList(),
    val error: String? = null,
)

/**
 * Past surveys, to share again: every session on this phone that has ended with
 * fingerprints (finished, or stopped early with data; not the empty sessions that carry a
 * team's plans), any one shared as CSV or JSON, and any set of them as survey bundles —
 * one file per building, since a bundle holds one building — for a coordinator who missed
 * the first share, or lost it.
 */
class PastSurveysModel(
    private val api: Trailprint,
    private val exports: ExportFiles,
    private val scope: CoroutineScope,
) {
    private val _state = MutableStateFlow(PastSurveysState())
    val state: StateFlow<PastSurveysState> = _state.asStateFlow()

    fun refresh() = busy {
        val list = api.buildings().flatMap { b ->
            api.sessions(b.id)
                .filter { it.status == SessionStatus.FINISHED || (it.status == SessionStatus.ABORTED && it.collected > 0uL) }
                .map { PastSurvey(it.id, b.id, b.name, it.createdMs, it.status, it.collected.toLong()) }
        }.sortedWith(compareByDescending<PastSurvey> { it.createdMs }.thenByDescending { it.sessionId })
        val ids = list.map { it.sessionId }.toSet()
        _state.update { it.copy(surveys = list, selected = it.selected intersect ids) }
    }

    fun toggle(sessionId: Long) = _state.update {
        it.copy(selected = if (sessionId in it.selected) it.selected - sessionId else it.selected + sessionId)
    }

    fun shareCsv(sessionId: Long) = busy { _state.update { it.copy(share = listOf(exports.sessionCsv(sessionId))) } }

    fun shareJson(sessionId: Long) = busy { _state.update { it.copy(share = listOf(exports.sessionJson(sessionId))) } }

    /** The ticked sessions as bundles, one per building, with this [device]'s and [surveyorName]'s names. */
    fun shareSelectedBundles(device: String?, surveyorName: String?) = busy {
        val s = _state.value
        val chosen = s.surveys.filter { it.sessionId in s.selected }
        if (chosen.isEmpty()) throw AppException("tick the surveys to put in the bundle first")
        val name = surveyorName?.trim()?.ifEmpty { null }
        val files = chosen.groupBy { it.buildingId }.values.map { group ->
            exports.sessionsBundle(group.map { it.sessionId }, device, name)
        }
        _state.update { it.copy(share = files) }
    }

    /** The share sheet was shown. */
    fun shared() = _state.update { it.copy(share = emptyList()) }

    fun dismissError() = _state.update { it.copy(error = null) }

    private fun busy(block: suspend () -> Unit) = scope.launch { _state.runBusy({ copy(busy = it) }, { copy(error = it) }, block) }
}
