package dev.trailprint.ui

import dev.trailprint.Trailprint
import dev.trailprint.ffi.BuildingMap
import dev.trailprint.ffi.PlanSummary
import dev.trailprint.ffi.SessionStatus
import dev.trailprint.ffi.SessionSummary
import dev.trailprint.ffi.SurveyorProfile
import dev.trailprint.ffi.TrailprintException
import dev.trailprint.ffi.Turn
import dev.trailprint.geometry.WorldPoint
import dev.trailprint.survey.SurveyController
import dev.trailprint.survey.SurveyLive
import kotlinx.coroutines.CoroutineDispatcher
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Dispatchers
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
    val plannedNats: Double = 0.0,
    val scanMessage: String? = null,
    val finished: SessionSummary? = null,
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
                plannedNats = p?.plannedUtilityNats ?: 0.0,
                scanMessage = live.scans?.message(),
                finished = live.summary,
                error = live.error,
            )
        }
    }
}

/**
 * State of the survey screen: starts (or resumes) the session, owns its
 * [SurveyController], and maps the controller's state to [SurveyUiState]. The Android
 * ViewModel attaches the sensors (or a robot) to [controller].
 */
class SurveyModel(
    private val api: Trailprint,
    private val scope: CoroutineScope,
    private val io: CoroutineDispatcher = Dispatchers.IO,
    private val clock: () -> Long = System::currentTimeMillis,
) {
    private val _state = MutableStateFlow(SurveyUiState())
    val state: StateFlow<SurveyUiState> = _state.asStateFlow()

    var controller: SurveyController? = null
        private set

    /** Starts a session on [planId] for [surveyor] (or resumes [resumeSessionId]). */
    fun start(
        planId: Long,
        surveyor: SurveyorProfile,
        resumeSessionId: Long? = null,
        onReady: suspend (SurveyController, BuildingMap) -> Unit = { _, _ -> },
    ) = scope.launch {
        try {
            val plan = api.plan(planId)
            val map = api.map(plan.buildingId)
            val session = if (resumeSessionId != null) api.resumeSession(resumeSessionId) else api.startSession(planId, surveyor)
            val c = SurveyController(session, scope, io, clock)
            controller = c
            c.refresh()
            onReady(c, map)
            val sid = session.id()
            c.state.collect { live ->
                val ahead = try {
                    session.routeAhead().map { it.vertex }
                } catch (e: Exception) {
                    emptyList()
                }
                _state.value = SurveyUiState.of(map, plan, sid, live, ahead)
            }
        } catch (e: TrailprintException) {
            _state.update { it.copy(error = e.message) }
        }
    }

    fun checkIn() = scope.launch { controller?.checkInAtNext() }

    fun checkInAt(vertex: String) = scope.launch { controller?.checkIn(vertex) }

    fun pause() = scope.launch { controller?.pause() }

    fun resume() = scope.launch { controller?.resume() }

    fun replan() = scope.launch {
        _state.update { it.copy(busy = true) }
        controller?.replan()
        _state.update { it.copy(busy = false) }
    }

    fun finish() = scope.launch { controller?.finish() }

    /** Shows an error from outside the session (for example the robot link). */
    fun reportError(message: String) = _state.update { it.copy(error = message) }

    fun dismissError() {
        controller?.dismissError()
        _state.update { it.copy(error = null) }
    }
}
