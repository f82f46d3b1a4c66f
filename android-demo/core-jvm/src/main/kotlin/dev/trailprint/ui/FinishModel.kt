package dev.trailprint.ui

import dev.trailprint.AppException
import dev.trailprint.Trailprint
import dev.trailprint.files.ExportFiles
import dev.trailprint.files.ShareableFile
import dev.trailprint.ffi.SessionSummary
import dev.trailprint.ffi.TrailprintException
import dev.trailprint.runBusy
import kotlinx.coroutines.CoroutineDispatcher
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asStateFlow
import kotlinx.coroutines.flow.update
import kotlinx.coroutines.launch
import kotlinx.coroutines.withContext

data class FinishState(
    val summary: SessionSummary? = null,
    val buildingId: Long? = null,
    /** A file being written for sharing. */
    val busy: Boolean = false,
    /** The file to share now (the screen starts the share sheet and calls [FinishModel.shared]). */
    val share: ShareableFile? = null,
    val error: String? = null,
) {
    /** The lines of the summary card. */
    fun lines(): List<String> = summary?.let { s ->
        listOf(
            "Walked %.0f m of %.0f m in %.0f min".format(s.walkedM, s.budgetM, s.elapsedS / 60),
            "%d fingerprints, %d check-ins, %d replans".format(s.samples.toLong(), s.checkIns.toInt(), s.replans.toInt()),
            if (s.sampleBlock > 1uL) {
                // Past the memory budget the figures keep one scan of every sampleBlock.
                "Information: at least %.1f nats collected (one fingerprint in %d counted, memory budget), %.1f planned"
                    .format(s.collectedUtilityNats, s.sampleBlock.toLong(), s.plannedUtilityNats)
            } else {
                "Information: %.1f nats collected, %.1f planned".format(s.collectedUtilityNats, s.plannedUtilityNats)
            },
            "Radio map uncertainty: mean %.1f dB, worst %.1f dB".format(s.meanStdDb, s.maxStdDb),
            "Step length learnt: %.2f m".format(s.stepLengthM),
        )
    } ?: emptyList()
}

/**
 * State of the finish screen: the summary of a session, and its data as files to share —
 * the fingerprints as CSV or JSON, and the building's survey bundle for the team's
 * coordinator. Files are written on demand by [exports], never held as text in the state.
 */
class FinishModel(
    private val api: Trailprint,
    private val exports: ExportFiles,
    private val scope: CoroutineScope,
    private val io: CoroutineDispatcher = Dispatchers.IO,
) {
    private val _state = MutableStateFlow(FinishState())
    val state: StateFlow<FinishState> = _state.asStateFlow()
    private var sessionId: Long? = null

    fun load(sessionId: Long) = scope.launch {
        this@FinishModel.sessionId = sessionId
        try {
            val session = api.resumeSession(sessionId)
            val (summary, bid) = withContext(io) { session.use { it.summary() to it.buildingId() } }
            _state.update { it.copy(summary = summary, buildingId = bid) }
        } catch (e: TrailprintException) {
            _state.update { it.copy(error = e.message) }
        }
    }

    fun shareCsv() = export { exports.sessionCsv(it) }

    fun shareJson() = export { exports.sessionJson(it) }

    /**
     * The bundle of this survey's session (not every session the phone holds of the
     * building: those it imported from the team are the coordinator's already), named
     * after this [device] and [surveyorName].
     */
    fun shareBundle(device: String?, surveyorName: String?) = export { sid ->
        if (_state.value.buildingId == null) throw AppException("the session is not loaded yet")
        exports.sessionsBundle(listOf(sid), device, surveyorName?.trim()?.ifEmpty { null })
    }

    /** The share sheet was shown. */
    fun shared() = _state.update { it.copy(share = null) }

    fun dismissError() = _state.update { it.copy(error = null) }

    private fun export(make: suspend (Long) -> ShareableFile) = scope.launch {
        val sid = sessionId ?: return@launch
        _state.runBusy({ copy(busy = it) }, { copy(error = it) }) {
            val f = make(sid)
            _state.update { it.copy(share = f) }
        }
    }
}
