package dev.trailprint.ui

import dev.trailprint.PlanEvent
import dev.trailprint.RunningPlan
import dev.trailprint.Trailprint
import dev.trailprint.ffi.BuildingMap
import dev.trailprint.ffi.BuildingSummary
import dev.trailprint.ffi.PlanAlgorithm
import dev.trailprint.ffi.PlanProgress
import dev.trailprint.ffi.PlanRequest
import dev.trailprint.ffi.PlanSummary
import dev.trailprint.ffi.SurveyorProfile
import dev.trailprint.ffi.TrailprintException
import dev.trailprint.ffi.defaultHumanProfile
import dev.trailprint.ffi.defaultRobotProfile
import kotlinx.coroutines.CancellationException
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Job
import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asStateFlow
import kotlinx.coroutines.flow.update
import kotlinx.coroutines.launch

enum class BudgetUnit { METRES, MINUTES }

enum class Profile { HUMAN, ROBOT }

/** A part of a building to plan instead of the whole: what lies within [radiusM] of [around]. */
data class PartSuggestion(val around: String, val radiusM: Double)

/** The plan screen. */
data class PlanState(
    val map: BuildingMap? = null,
    val start: String? = null,
    val end: String? = null,
    val budget: Double = 60.0,
    val unit: BudgetUnit = BudgetUnit.METRES,
    val profile: Profile = Profile.HUMAN,
    val human: SurveyorProfile.Human = defaultHumanProfile() as SurveyorProfile.Human,
    val robot: SurveyorProfile.Robot = defaultRobotProfile() as SurveyorProfile.Robot,
    val algorithm: PlanAlgorithm = PlanAlgorithm.AUTO,
    val planning: Boolean = false,
    val progress: PlanProgress? = null,
    val result: PlanSummary? = null,
    val error: String? = null,
    /**
     * After a plan the time limit could not hold (a robot's long walk on a large floor, on
     * a slow phone): the limit, seconds, the planner says would do. The screen offers
     * "plan with this much time" ([PlanModel.planWithSuggestedTime]).
     */
    val suggestedTimeLimitS: Double? = null,
    /**
     * After a plan refused because the building needs more memory than the phone allows:
     * the part the planner says holds every vertex the walk can reach. The screen offers
     * "plan this part" ([PlanModel.planSuggestedPart]).
     */
    val suggestedPart: PartSuggestion? = null,
    /** The part imported by [PlanModel.planSuggestedPart]: the screen opens its plan. */
    val partBuilding: BuildingSummary? = null,
) {
    val surveyor: SurveyorProfile get() = if (profile == Profile.HUMAN) human else robot

    /** Walking (driving) speed, m/s: the robot's is assumed 0.5 m/s for a budget in minutes. */
    val speedMps: Double get() = if (profile == Profile.HUMAN) human.speedMps else ROBOT_SPEED_MPS

    /** The budget in metres (minutes times speed). */
    val budgetMetres: Double get() = if (unit == BudgetUnit.METRES) budget else budget * 60.0 * speedMps

    val canPlan: Boolean get() = map != null && start != null && end != null && budget > 0 && !planning

    companion object {
        const val ROBOT_SPEED_MPS = 0.5

        private val SUGGESTED_PART = Regex("""--around (\S+) --radius ([0-9]+(?:\.[0-9]+)?)""")

        /** The part that a refusal's [message] names (`--around V --radius M`), if any. */
        fun suggestedPart(message: String?): PartSuggestion? =
            message?.let { SUGGESTED_PART.find(it) }?.let { m ->
                m.groupValues[2].toDoubleOrNull()?.let { PartSuggestion(m.groupValues[1], it) }
            }

        private val SUGGESTED_LIMIT = Regex("""raise the time limit \([^)]*\) to ([0-9]+(?:\.[0-9]+)?) s or more""")

        /** The time limit, seconds, that a time-limit refusal's [message] names, if any. */
        fun suggestedTimeLimit(message: String?): Double? =
            message?.let { SUGGESTED_LIMIT.find(it)?.groupValues?.get(1)?.toDoubleOrNull() }
    }
}

/**
 * State of the plan screen: pick start and end on the map (the first tap sets the start,
 * the second the end, a third starts over), budget in metres or minutes, surveyor
 * profile, algorithm; plan with progress and cancel.
 */
class PlanModel(
    private val api: Trailprint,
    private val scope: CoroutineScope,
    val buildingId: Long,
    private val seed: ULong = 1u,
) {
    private val _state = MutableStateFlow(PlanState())
    val state: StateFlow<PlanState> = _state.asStateFlow()
    private var planJob: Job? = null
    @Volatile private var runningPlan: RunningPlan? = null

    fun load() = scope.launch {
        try {
            val map = api.map(buildingId)
            _state.update { it.copy(map = map) }
        } catch (e: TrailprintException) {
            _state.update { it.copy(error = e.message) }
        }
    }

    /** A tap on vertex [id]. */
    fun tapVertex(id: String) = _state.update {
        when {
            it.start == null -> it.copy(start = id, result = null)
            it.end == null -> it.copy(end = id, result = null)
            else -> it.copy(start = id, end = null, result = null)
        }
    }

    fun setBudget(value: Double) = _state.update { it.copy(budget = value) }

    /** Switches the unit, converting the number so the budget stays the same. */
    fun setUnit(unit: BudgetUnit) = _state.update {
        if (unit == it.unit) it
        else {
            val metres = it.budgetMetres
            it.copy(unit = unit, budget = if (unit == BudgetUnit.METRES) metres else metres / 60.0 / it.speedMps)
        }
    }

    fun setProfile(profile: Profile) = _state.update { it.copy(profile = profile) }

    fun setHuman(human: SurveyorProfile.Human) = _state.update { it.copy(human = human) }

    fun setAlgorithm(algorithm: PlanAlgorithm) = _state.update { it.copy(algorithm = algorithm) }

    /** Plans again with the time limit the last refusal named (nothing when there is none). */
    fun planWithSuggestedTime() {
        val limit = _state.value.suggestedTimeLimitS ?: return
        plan(limit)
    }

    fun plan(timeLimitS: Double? = null) {
        val s = _state.value
        if (!s.canPlan) return
        val request = PlanRequest(buildingId, s.start!!, s.end!!, s.budgetMetres, s.surveyor, s.algorithm, seed, timeLimitS)
        _state.update {
            it.copy(planning = true, progress = null, result = null, error = null, suggestedTimeLimitS = null, suggestedPart = null)
        }
        val running = api.startPlan(request)
        runningPlan = running
        planJob = scope.launch {
            try {
                running.events.collect { ev ->
                    when (ev) {
                        is PlanEvent.Progress -> _state.update { it.copy(progress = ev.progress) }
                        is PlanEvent.Done -> _state.update { it.copy(result = ev.plan) }
                    }
                }
            } catch (e: TrailprintException.Cancelled) {
                // The user cancelled: nothing to show.
            } catch (e: TrailprintException.TimeLimitTooShort) {
                _state.update { it.copy(error = e.message, suggestedTimeLimitS = PlanState.suggestedTimeLimit(e.message)) }
            } catch (e: TrailprintException.InvalidRequest) {
                _state.update { it.copy(error = e.message, suggestedPart = PlanState.suggestedPart(e.message)) }
            } catch (e: TrailprintException) {
                _state.update { it.copy(error = e.message) }
            } catch (e: CancellationException) {
                throw e
            } finally {
                _state.update { it.copy(planning = false) }
                if (runningPlan === running) runningPlan = null
            }
        }
    }

    /**
     * Cancels a running plan: the native planner stops and its best walk so far becomes
     * the result (termination "cancelled"), so the minutes already spent are not lost.
     */
    fun cancel() {
        runningPlan?.stop()
    }

    /**
     * Imports the part the last refusal named (the building imported before when the same
     * part was asked for already) and puts it in [PlanState.partBuilding], for the screen to open its
     * plan. Nothing when there is no suggestion.
     */
    fun planSuggestedPart() {
        val part = _state.value.suggestedPart ?: return
        _state.update { it.copy(error = null, suggestedPart = null) }
        scope.launch {
            try {
                val b = api.importBuildingPart(buildingId, around = part.around, radiusM = part.radiusM)
                _state.update { it.copy(partBuilding = b) }
            } catch (e: TrailprintException) {
                _state.update { it.copy(error = e.message) }
            }
        }
    }

    /** The screen opened [PlanState.partBuilding]: forget it, so that coming back here stays here. */
    fun partOpened() = _state.update { it.copy(partBuilding = null) }

    fun dismissError() = _state.update { it.copy(error = null, suggestedTimeLimitS = null, suggestedPart = null) }
}
