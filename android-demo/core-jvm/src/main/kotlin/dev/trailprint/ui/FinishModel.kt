package dev.trailprint.ui

import dev.trailprint.Trailprint
import dev.trailprint.ffi.SessionSummary
import dev.trailprint.ffi.TrailprintException
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
    /** The collected fingerprints, ready to share. */
    val exportJson: String? = null,
    val exportCsv: String? = null,
    val error: String? = null,
) {
    /** The lines of the summary card. */
    fun lines(): List<String> = summary?.let { s ->
        listOf(
            "Walked %.0f m of %.0f m in %.0f min".format(s.walkedM, s.budgetM, s.elapsedS / 60),
            "%d fingerprints, %d check-ins, %d replans".format(s.samples.toLong(), s.checkIns.toInt(), s.replans.toInt()),
            "Information: %.1f nats collected, %.1f planned".format(s.collectedUtilityNats, s.plannedUtilityNats),
            "Radio map uncertainty: mean %.1f dB, worst %.1f dB".format(s.meanStdDb, s.maxStdDb),
            "Step length learnt: %.2f m".format(s.stepLengthM),
        )
    } ?: emptyList()
}

/** State of the finish screen: the summary and the exports of a session. */
class FinishModel(
    private val api: Trailprint,
    private val scope: CoroutineScope,
    private val io: CoroutineDispatcher = Dispatchers.IO,
) {
    private val _state = MutableStateFlow(FinishState())
    val state: StateFlow<FinishState> = _state.asStateFlow()

    fun load(sessionId: Long) = scope.launch {
        try {
            val session = api.resumeSession(sessionId)
            val (summary, json, csv) = withContext(io) {
                session.use { Triple(it.summary(), it.exportJson(), it.exportCsv()) }
            }
            _state.update { it.copy(summary = summary, exportJson = json, exportCsv = csv) }
        } catch (e: TrailprintException) {
            _state.update { it.copy(error = e.message) }
        }
    }
}
