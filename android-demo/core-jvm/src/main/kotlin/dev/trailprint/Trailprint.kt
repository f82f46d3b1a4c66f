package dev.trailprint

import dev.trailprint.ffi.BuildingMap
import dev.trailprint.ffi.BuildingSummary
import dev.trailprint.ffi.FitSummary
import dev.trailprint.ffi.PlanListener
import dev.trailprint.ffi.PlanProgress
import dev.trailprint.ffi.PlanRequest
import dev.trailprint.ffi.PlanSummary
import dev.trailprint.ffi.SessionInfo
import dev.trailprint.ffi.SessionOptions
import dev.trailprint.ffi.SurveySession
import dev.trailprint.ffi.SurveyorProfile
import dev.trailprint.ffi.BundleImportSummary
import dev.trailprint.ffi.TeamPlanRequest
import dev.trailprint.ffi.TeamPlanSummary
import dev.trailprint.ffi.TrailprintStore
import dev.trailprint.ffi.defaultSessionOptions
import kotlinx.coroutines.CoroutineDispatcher
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.channels.awaitClose
import kotlinx.coroutines.flow.Flow
import kotlinx.coroutines.flow.callbackFlow
import kotlinx.coroutines.launch
import kotlinx.coroutines.withContext

/** What a running plan reports: progress, then exactly one [Done] (or the flow fails). */
sealed interface PlanEvent {
    data class Progress(val progress: PlanProgress) : PlanEvent
    data class Done(val plan: PlanSummary) : PlanEvent
}

/** A plan being computed: its [events] (collect once) and a [stop] that keeps the best walk. */
class RunningPlan internal constructor(val events: Flow<PlanEvent>, private val onStop: () -> Unit) {
    /** Stops the planner; [events] then ends with the best walk found so far. */
    fun stop() = onStop()
}

/**
 * What a running team plan reports: each planning run's progress (its message names the
 * member and the run, `surveyor 2/3, in turn: ...`), then exactly one [Done].
 */
sealed interface TeamPlanEvent {
    data class Progress(val progress: PlanProgress) : TeamPlanEvent
    data class Done(val team: TeamPlanSummary) : TeamPlanEvent
}

/** A team plan being computed: its [events] (collect once) and a [stop] that keeps the walks so far. */
class RunningTeamPlan internal constructor(val events: Flow<TeamPlanEvent>, private val onStop: () -> Unit) {
    /**
     * Stops the team plan; [events] then ends with a walk for every member (the planning
     * under way keeps its best walk, a member not yet planned gets the systematic walk),
     * saved, with `cancelled` set.
     */
    fun stop() = onStop()
}

/**
 * The hand-written Kotlin face of Trailprint: suspend functions that run the (blocking)
 * native calls on [io], and planning as a cold [Flow] of [PlanEvent]s whose cancellation
 * cancels the native plan. Errors arrive as `TrailprintException` subclasses.
 *
 * One instance per database file; safe to share between view models.
 *
 * [memoryBudgetMb] is what the device allows the engine, MiB ([DeviceMemory.budgetMb] on a
 * phone; null: the library's default, 512): every plan, team plan and session started
 * here gets it, unless its request or options already name a budget.
 */
class Trailprint(
    val store: TrailprintStore,
    private val io: CoroutineDispatcher = Dispatchers.IO,
    val memoryBudgetMb: ULong? = null,
) : AutoCloseable {
    companion object {
        /** Opens (or creates) the database at [path]. */
        suspend fun open(path: String, io: CoroutineDispatcher = Dispatchers.IO, memoryBudgetMb: ULong? = null): Trailprint =
            withContext(io) { Trailprint(TrailprintStore.open(path), io, memoryBudgetMb) }

        /** A database in memory (tests and previews). */
        fun inMemory(io: CoroutineDispatcher = Dispatchers.IO, memoryBudgetMb: ULong? = null): Trailprint =
            Trailprint(TrailprintStore.openInMemory(), io, memoryBudgetMb)
    }

    /** [request] with this instance's [memoryBudgetMb] when it names none. */
    internal fun budgeted(request: PlanRequest): PlanRequest =
        if (memoryBudgetMb == null || request.memoryBudgetMb != null) request else request.copy(memoryBudgetMb = memoryBudgetMb)

    /** [request] with this instance's [memoryBudgetMb] when it names none. */
    internal fun budgeted(request: TeamPlanRequest): TeamPlanRequest =
        if (memoryBudgetMb == null || request.memoryBudgetMb != null) request else request.copy(memoryBudgetMb = memoryBudgetMb)

    /**
     * The options a session started here runs with: [options] (the core's defaults when
     * null) with this instance's [memoryBudgetMb] unless [options] names a budget.
     */
    internal fun budgeted(options: SessionOptions?): SessionOptions? = when {
        memoryBudgetMb == null -> options
        options == null -> defaultSessionOptions().copy(memoryBudgetMb = memoryBudgetMb)
        options.memoryBudgetMb == null -> options.copy(memoryBudgetMb = memoryBudgetMb)
        else -> options
    }

    suspend fun importBuilding(json: String, origin: String, replace: Boolean = false): BuildingSummary =
        withContext(io) { store.importBuildingJson(json, origin, replace) }

    suspend fun importBuildingFile(path: String, replace: Boolean = false): BuildingSummary =
        withContext(io) { store.importBuildingFile(path, replace) }

    /**
     * Imports a part of building [buildingId] as a building of its own: the [floors] (all
     * when empty) and, with [around] and [radiusM], what lies within that walk of the vertex.
     * A building refused for memory is planned by parts ([dev.trailprint.ui.PlanModel.planSuggestedPart]).
     */
    suspend fun importBuildingPart(
        buildingId: Long,
        floors: List<Long> = emptyList(),
        around: String? = null,
        radiusM: Double? = null,
        name: String? = null,
        replace: Boolean = false,
    ): BuildingSummary = withContext(io) { store.importBuildingPart(buildingId, floors, around, radiusM, name, replace) }

    suspend fun buildings(): List<BuildingSummary> = withContext(io) { store.listBuildings() }

    suspend fun map(buildingId: Long): BuildingMap = withContext(io) { store.buildingMap(buildingId) }

    suspend fun deleteBuilding(buildingId: Long) = withContext(io) { store.deleteBuilding(buildingId) }

    suspend fun fit(buildingId: Long): FitSummary = withContext(io) { store.fit(buildingId) }

    suspend fun plans(buildingId: Long): List<PlanSummary> = withContext(io) { store.listPlans(buildingId) }

    suspend fun plan(planId: Long): PlanSummary = withContext(io) { store.getPlan(planId) }

    /**
     * Plans [request]: progress events while it runs, then [PlanEvent.Done] with the saved
     * plan. Cancelling the collector cancels the native planner: it stops within one of
     * its progress checks and saves its best walk so far (`termination` = `cancelled`).
     */
    fun plan(request: PlanRequest): Flow<PlanEvent> = startPlan(request).events

    /**
     * Starts planning [request] and returns at once. [RunningPlan.stop] stops the planner
     * the way a user's Cancel should: [RunningPlan.events] still ends with [PlanEvent.Done],
     * carrying the best walk found so far (termination "cancelled"), saved like any plan.
     * Cancelling the collecting coroutine instead stops the planner and drops the result.
     */
    fun startPlan(request: PlanRequest): RunningPlan = store.newPlan(budgeted(request)).let { job ->
        val (events, stop) = running(job::run, job::cancel, job::close, PlanEvent::Progress, PlanEvent::Done)
        RunningPlan(events, stop)
    }

    /**
     * Starts planning a team and returns at once, as [startPlan] does for one walk:
     * [RunningTeamPlan.stop] is the user's Cancel (the walks so far are saved and returned),
     * cancelling the collecting coroutine stops the planner and drops the result.
     */
    fun startTeamPlan(request: TeamPlanRequest): RunningTeamPlan = store.newTeamPlan(budgeted(request)).let { job ->
        val (events, stop) = running(job::run, job::cancel, job::close, TeamPlanEvent::Progress, TeamPlanEvent::Done)
        RunningTeamPlan(events, stop)
    }

    /**
     * A native planning call as a cold flow: [run] on [io] with a listener that forwards
     * progress, then one [toDone] event. Closing the flow cancels the call and frees the
     * native object once; the returned stop cancels it and lets the flow end with [toDone].
     */
    private fun <R, E> running(
        run: (PlanListener?) -> R,
        cancelJob: () -> Unit,
        closeJob: () -> Unit,
        toProgress: (PlanProgress) -> E,
        toDone: (R) -> E,
    ): Pair<Flow<E>, () -> Unit> {
        val closed = java.util.concurrent.atomic.AtomicBoolean(false)
        val events = callbackFlow {
            val listener = object : PlanListener {
                override fun onProgress(progress: PlanProgress) {
                    trySend(toProgress(progress))
                }
            }
            launch(io) {
                try {
                    val result = run(listener)
                    send(toDone(result))
                    close()
                } catch (e: Exception) {
                    close(e)
                }
            }
            awaitClose {
                cancelJob()
                // Safe while run() is still going: the native object lives until that call returns.
                if (closed.compareAndSet(false, true)) closeJob()
            }
        }
        return events to { if (!closed.get()) cancelJob() }
    }

    /**
     * Starts a survey session on a saved plan, within [memoryBudgetMb] unless [options]
     * names a budget (its replans may use all of it, its running figures half).
     */
    suspend fun startSession(planId: Long, surveyor: SurveyorProfile, options: SessionOptions? = null): SurveySession =
        withContext(io) { store.startSession(planId, surveyor, budgeted(options)) }

    /** Reopens a stored session where its log ends. */
    suspend fun resumeSession(sessionId: Long): SurveySession = withContext(io) { store.resumeSession(sessionId) }

    suspend fun sessions(buildingId: Long): List<SessionInfo> = withContext(io) { store.listSessions(buildingId) }

    /** Plans walks for several surveyors that complement each other; one saved plan per member. */
    suspend fun planTeam(request: TeamPlanRequest): TeamPlanSummary = withContext(io) { store.planTeam(budgeted(request)) }

    /** A bundle of the building's survey sessions (JSON text) to share with another device. */
    suspend fun exportBundle(buildingId: Long, device: String? = null, surveyorName: String? = null): String =
        withContext(io) { store.exportBundle(buildingId, device, surveyorName) }

    /**
     * A bundle of exactly the sessions [sessionIds] (all of one building: a bundle holds
     * one), for sharing chosen surveys; an empty list or a foreign id is an error naming it.
     */
    suspend fun exportSessionsBundle(sessionIds: List<Long>, device: String? = null, surveyorName: String? = null): String =
        withContext(io) { store.exportSessionsBundle(sessionIds, device, surveyorName) }

    /** Merges a bundle from another device; importing it again changes nothing. */
    suspend fun importBundle(json: String, origin: String): BundleImportSummary =
        withContext(io) { store.importBundle(json, origin) }

    override fun close() = store.close()
}
