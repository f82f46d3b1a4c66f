package dev.trailprint.ui

import dev.trailprint.ffi.BuildingMap
import dev.trailprint.ffi.PlanSummary
import dev.trailprint.ffi.SessionStatus
import dev.trailprint.ffi.SessionSummary
import dev.trailprint.ffi.TrailprintException
import dev.trailprint.ffi.Turn
import dev.trailprint.geometry.WorldPoint
import dev.trailprint.AppException
import dev.trailprint.survey.LifecycleState
import dev.trailprint.survey.SurveyLifecycle
import dev.trailprint.survey.SurveyLive
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asStateFlow
import kotlinx.coroutines.flow.update
import kotlinx.coroutines.launch

/** Everything the survey screen draws. */
data class SurveyUiState(
    val map: BuildingMap? = null,
    val plan: PlanSummary? = null,
    val sessionId: Long? = null,
    /** The walk still ahead, from the current estimate. */
    val planned: List<WorldPoint> = emptyList(),
    /** Estimates after each event. */
    val walked: List<WorldPoint> = emptyList(),
    val estimate: WorldPoint? = null,
    val next: WorldPoint? = null,
    val nextVertex: String? = null,
    val turn: Turn? = null,
    /** The core's one-sentence guidance. */
    val instruction: String = "",
    val distanceToNextM: Double = 0.0,
    val checkInDue: Boolean = false,
    val offRoute: Boolean = false,
    val paused: Boolean = false,
    val fraction: Double = 0.0,
    val samples: Long = 0,
    val collectedNats: Double = 0.0,
    /**
     * [collectedNats] is a lower bound: the session reached its memory budget and its
     * figures count one fingerprint of every `SessionProgress.sampleBlock` (show "≥").
     */
    val collectedIsLowerBound: Boolean = false,
    val plannedNats: Double = 0.0,
    val scanMessage: String? = null,
    /** What the survey costs in CPU time so far (see `AwakeMeter`). */
    val awakeMessage: String? = null,
    /** A note from the survey's lifecycle (carried on after a restart, a robot error). */
    val notice: String? = null,
    val finished: SessionSummary? = null,
    /** The active-survey record cannot be read: show it with a "Forget" button ([SurveyModel.forgetRecord]). */
    val unreadableRecord: String? = null,
    val busy: Boolean = false,
    val error: String? = null,
) {
    companion object {
        /** Pure: the screen state from the map, the plan and the controller's state. */
        fun of(map: BuildingMap, plan: PlanSummary?, sessionId: Long?, live: SurveyLive, ahead: List<String>): SurveyUiState {
            val byId = map.vertices.associateBy { it.id }
            val g = live.guidance
            val p = live.progress
            val walked = live.track.map { WorldPoint(it.x, it.y) }
            val estimate = walked.lastOrNull() ?: plan?.walk?.firstOrNull()?.let(byId::get)?.let { WorldPoint(it.x, it.y) }
            val aheadPts = ahead.mapNotNull(byId::get).map { WorldPoint(it.x, it.y) }
            return SurveyUiState(
                map = map,
                plan = plan,
                sessionId = sessionId,
                planned = listOfNotNull(estimate) + aheadPts,
                walked = walked,
                estimate = estimate,
                next = g?.nextVertex?.let(byId::get)?.let { WorldPoint(it.x, it.y) },
                nextVertex = g?.nextVertex,
                turn = g?.turn,
                instruction = g?.message ?: "",
                distanceToNextM = g?.distanceM ?: 0.0,
                checkInDue = g?.checkInAtNext == true && (g.distanceM < 3.0),
                offRoute = g?.offRoute == true,
                paused = live.status == SessionStatus.PAUSED,
                fraction = p?.fractionDone ?: 0.0,
                samples = p?.samples?.toLong() ?: 0,
                collectedNats = p?.collectedUtilityNats ?: 0.0,
                collectedIsLowerBound = p != null && p.sampleBlock > 1uL,
                plannedNats = p?.plannedUtilityNats ?: 0.0,
                scanMessage = live.scans?.message(),
                awakeMessage = live.awake?.message(),
                finished = live.summary,
                error = live.error,
            )
        }
    }
}

/**
 * State of the survey screen over the survey's [SurveyLifecycle], which the foreground
 * service owns: the screen binds to the service, draws [state] and sends the surveyor's
 * taps. Closing the screen does not stop the survey.
 */
class SurveyModel(private val lifecycle: SurveyLifecycle, private val scope: CoroutineScope) {
    private val _state = MutableStateFlow(SurveyUiState())
    val state: StateFlow<SurveyUiState> = _state.asStateFlow()
    private val lock = Any()
    private var error: String? = null
    private var busy = false
    /** The session this screen saw running: only its end is this screen's [SurveyUiState.finished]. */
    private var seen: Long? = null

    /** True while a survey runs (the screen shows it instead of starting another). */
    val hasActiveSurvey: Boolean get() = lifecycle.state.value.active != null

    // Every change of the lifecycle redraws from its latest state.
    private val watcher = scope.launch { lifecycle.state.collect { publish() } }

    /** Stops drawing (the screen is gone); operations already started run to their end. */
    fun close() = watcher.cancel()

    /**
     * Recomputes the screen from the lifecycle's *current* state (read and written under
     * one lock, so that a slower caller never overwrites a newer state with an older one).
     */
    private fun publish() = synchronized(lock) {
        val ls = lifecycle.state.value
        ls.active?.let { seen = it.sessionId }
        val map = ls.map
        val ui = if (map == null) SurveyUiState() else SurveyUiState.of(map, ls.plan, ls.active?.sessionId ?: ls.summary?.sessionId, ls.live, ls.ahead)
        _state.value = ui.copy(
            notice = ls.message,
            finished = (ls.summary ?: ui.finished)?.takeIf { it.sessionId == seen },
            unreadableRecord = ls.unreadableRecord,
            busy = busy,
            error = error ?: ui.error,
        )
    }

    fun checkIn() = act { lifecycle.controller?.checkInAtNext() }

    fun checkInAt(vertex: String) = act { lifecycle.controller?.checkIn(vertex) }

    fun pause() = act { lifecycle.pause() }

    fun resume() = act { lifecycle.resume() }

    fun replan() = act {
        synchronized(lock) { busy = true }
        publish()
        try {
            lifecycle.controller?.replan()
        } finally {
            synchronized(lock) { busy = false }
        }
    }

    fun finish() = act { lifecycle.stop() }

    /** Forgets an unreadable active-survey record (its session's data stay in the database). */
    fun forgetRecord() = act { lifecycle.forgetActive() }

    fun abort(reason: String? = null) = act { lifecycle.abort(reason) }

    /** Shows an error from outside the survey. */
    fun reportError(message: String) {
        synchronized(lock) { error = message }
        publish()
    }

    fun dismissError() {
        synchronized(lock) { error = null }
        lifecycle.controller?.dismissError()
        lifecycle.dismissMessage()
        publish()
    }

    private fun act(block: suspend () -> Unit) = scope.launch {
        try {
            block()
        } catch (e: AppException) {
            synchronized(lock) { error = e.message }
        } catch (e: TrailprintException) {
            synchronized(lock) { error = e.message }
        }
        publish()
    }
}
