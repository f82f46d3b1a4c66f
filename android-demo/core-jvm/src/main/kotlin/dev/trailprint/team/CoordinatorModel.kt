package dev.trailprint.team

import dev.trailprint.AppException
import dev.trailprint.RunningTeamPlan
import dev.trailprint.TeamPlanEvent
import dev.trailprint.Trailprint
import dev.trailprint.files.ExportFiles
import dev.trailprint.files.ShareableFile
import dev.trailprint.ffi.BuildingMap
import dev.trailprint.ffi.BuildingSummary
import dev.trailprint.ffi.BundleImportSummary
import dev.trailprint.ffi.PlanAlgorithm
import dev.trailprint.ffi.PlanProgress
import dev.trailprint.ffi.SurveyorProfile
import dev.trailprint.ffi.TeamMember
import dev.trailprint.ffi.TeamPlanRequest
import dev.trailprint.ffi.TeamPlanSummary
import dev.trailprint.ffi.TrailprintException
import dev.trailprint.ffi.defaultHumanProfile
import dev.trailprint.json.Json
import dev.trailprint.json.JsonException
import dev.trailprint.json.path
import dev.trailprint.runBusy
import java.time.Instant
import java.time.ZoneId
import java.time.format.DateTimeFormatter
import kotlinx.coroutines.CoroutineDispatcher
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asStateFlow
import kotlinx.coroutines.flow.update
import kotlinx.coroutines.launch
import kotlinx.coroutines.withContext

/** One surveyor of the team to plan: where they start and end, how far they may walk. */
data class MemberSpec(val name: String?, val start: String, val end: String, val budgetM: Double)

/** What one imported bundle did on the coordinator's phone. */
data class BundleReceipt(
    val origin: String,
    /** Provenance written by the phone that exported it. */
    val device: String? = null,
    val surveyorName: String? = null,
    val summary: BundleImportSummary? = null,
    /** Fingerprints of the building before minus after the import. */
    val fingerprintsAdded: Long = 0,
    /** Why nothing was imported (the core's message, naming the file and the field). */
    val error: String? = null,
) {
    /** The line the coordinator reads. */
    fun line(): String {
        if (error != null) return "$origin: not imported — $error"
        val s = summary ?: return origin
        val who = listOfNotNull(surveyorName, device?.let { "on $it" }).joinToString(" ").ifEmpty { "unknown phone" }
        val parts = buildList {
            if (s.buildingCreated) add("new building ${s.building}")
            add("${s.sessionsAdded} new sessions")
            if (s.sessionsExtended > 0uL) add("${s.sessionsExtended} extended")
            if (s.sessionsUnchanged > 0uL) add("${s.sessionsUnchanged} already here")
            add("${s.eventsAdded} events")
            add("$fingerprintsAdded fingerprints")
        }
        return "$origin ($who): ${parts.joinToString(", ")}"
    }
}

/** A planned team: the core's plans and one walk file per member, ready to share. */
data class TeamResult(
    val label: String,
    val summary: TeamPlanSummary,
    val assignments: List<WalkAssignment>,
    val files: List<ShareableFile>,
)

data class CoordinatorState(
    val buildings: List<BuildingSummary> = emptyList(),
    /** Every bundle imported in this visit of the screen, newest last. */
    val receipts: List<BundleReceipt> = emptyList(),
    val buildingId: Long? = null,
    val map: BuildingMap? = null,
    val members: List<MemberSpec> = emptyList(),
    val algorithm: PlanAlgorithm = PlanAlgorithm.AUTO,
    val busy: Boolean = false,
    /** While the team is planned: which member and run, and the team's best so far. */
    val planProgress: String? = null,
    val team: TeamResult? = null,
    /** The file to share now (the screen starts the share sheet and calls [CoordinatorModel.shared]). */
    val share: ShareableFile? = null,
    val error: String? = null,
) {
    val building: BuildingSummary? get() = buildings.firstOrNull { it.id == buildingId }
    val canPlan: Boolean get() = buildingId != null && members.isNotEmpty() && !busy
}

/**
 * The coordinator's phone: merges the bundles the surveyors share (from the share sheet
 * or a file picker), shows what each added, and plans the next walks for N surveyors as a
 * team — walks that complement each other and what is already collected — each written
 * as a walk file ([WalkFiles]) to share with its surveyor.
 *
 * A bundle that fails (corrupt, truncated, another format) is reported on its own line
 * and imports nothing; the others still go in.
 */
class CoordinatorModel(
    private val api: Trailprint,
    private val exports: ExportFiles,
    private val scope: CoroutineScope,
    /** This phone's name, written into the bundles of the walk files. */
    private val device: String? = null,
    private val coordinatorName: String? = null,
    private val io: CoroutineDispatcher = Dispatchers.IO,
    private val clock: () -> Long = System::currentTimeMillis,
    private val surveyor: SurveyorProfile = defaultHumanProfile(),
    /** Seed of the team planner. */
    private val seed: ULong = 1u,
    private val timeLimitS: Double? = null,
) {
    private val _state = MutableStateFlow(CoordinatorState())

    /** The team plan under way, for [stopPlanning]. */
    @Volatile private var planning: RunningTeamPlan? = null
    val state: StateFlow<CoordinatorState> = _state.asStateFlow()

    fun refresh() = busy { _state.update { it.copy(buildings = api.buildings()) } }

    /** Imports bundles given as (file name, text), one after the other. */
    fun importBundles(files: List<Pair<String, String>>) = busy {
        for ((origin, text) in files) {
            val receipt = importOne(origin, text)
            val buildings = api.buildings()
            _state.update { s ->
                val chosen = s.buildingId ?: receipt.summary?.let { r -> buildings.firstOrNull { it.name == r.building }?.id }
                s.copy(receipts = s.receipts + receipt, buildings = buildings, buildingId = chosen)
            }
        }
        _state.value.buildingId?.let { loadMap(it) }
    }

    private suspend fun importOne(origin: String, text: String): BundleReceipt {
        val before = api.buildings()
        val summary = try {
            api.importBundle(text, origin)
        } catch (e: TrailprintException) {
            return BundleReceipt(origin, error = e.message)
        }
        val (device, name) = withContext(io) { provenance(text) }
        val after = api.buildings()
        fun collected(l: List<BuildingSummary>) = l.firstOrNull { it.name == summary.building }?.collected?.toLong() ?: 0L
        return BundleReceipt(origin, device, name, summary, collected(after) - collected(before))
    }

    /** Who exported a bundle (it already imported, so it parses). */
    private fun provenance(text: String): Pair<String?, String?> = try {
        val doc = Json.parse(text)
        (doc.path("body", "device") as? String) to (doc.path("body", "surveyor_name") as? String)
    } catch (e: JsonException) {
        null to null
    }

    fun selectBuilding(id: Long) = busy {
        _state.update { it.copy(buildingId = id, team = null) }
        loadMap(id)
    }

    private suspend fun loadMap(id: Long) {
        val map = api.map(id)
        _state.update { it.copy(map = map) }
    }

    /** [n] surveyors, all from [start] to [end] with [budgetM] metres each. */
    fun setTeam(n: Int, start: String, end: String, budgetM: Double) = _state.update {
        it.copy(members = List(n.coerceIn(0, 50)) { i -> MemberSpec("Surveyor ${i + 1}", start, end, budgetM) }, team = null)
    }

    fun setMember(index: Int, spec: MemberSpec) = _state.update {
        if (index !in it.members.indices) it else it.copy(members = it.members.toMutableList().also { m -> m[index] = spec }, team = null)
    }

    fun setAlgorithm(algorithm: PlanAlgorithm) = _state.update { it.copy(algorithm = algorithm) }

    /** Plans the team's walks and writes one walk file per member. */
    fun plan() = busy {
        val s = _state.value
        val bid = s.buildingId ?: throw AppException("choose a building first")
        if (s.members.isEmpty()) throw AppException("add at least one surveyor")
        s.members.forEachIndexed { i, m ->
            if (!(m.budgetM > 0)) throw AppException("surveyor ${i + 1}: budget must be a positive number of metres, got ${m.budgetM}")
        }
        val building = s.building ?: api.buildings().first { it.id == bid }
        val running = api.startTeamPlan(
            TeamPlanRequest(bid, s.members.map { TeamMember(it.start, it.end, it.budgetM) }, surveyor, s.algorithm, seed, timeLimitS, false),
        )
        planning = running
        var result: TeamPlanSummary? = null
        try {
            running.events.collect { e ->
                when (e) {
                    is TeamPlanEvent.Progress -> _state.update { it.copy(planProgress = progressLine(e.progress)) }
                    is TeamPlanEvent.Done -> result = e.team
                }
            }
        } finally {
            planning = null
            _state.update { it.copy(planProgress = null) }
        }
        val team = checkNotNull(result) { "the team plan ended without its result" }
        // One carrier session per plan, so that the bundle carries the plans (see WalkFiles).
        withContext(io) {
            team.planIds.forEachIndexed { i, planId ->
                api.startSession(planId, surveyor).use { c ->
                    c.abort(clock(), "carries team walk ${i + 1} of ${team.planIds.size} to its surveyor")
                }
            }
        }
        val bundle = api.exportBundle(bid, device, coordinatorName)
        val label = "${building.name} · ${team.planIds.size} surveyors · " +
            DateTimeFormatter.ofPattern("yyyy-MM-dd HH:mm").withZone(ZoneId.systemDefault()).format(Instant.ofEpochMilli(clock()))
        val assignments = team.planIds.indices.map { i ->
            val plan = api.plan(team.planIds[i])
            val m = s.members[i]
            WalkAssignment(label, i + 1, team.planIds.size, m.name, building.name, m.start, m.end, m.budgetM, plan.walk, plan.lengthM, plan.utilityNats)
        }
        val files = withContext(io) {
            assignments.map { a ->
                val who = ExportFiles.slug(a.surveyorName ?: "surveyor-${a.member}")
                exports.write(
                    "trailprint-${ExportFiles.slug(a.building)}-walk-${a.member}-of-${a.members}-$who.json",
                    WalkFiles.encode(a, bundle),
                    ExportFiles.JSON,
                    "Walk ${a.member} of ${a.members} for ${a.surveyorName ?: "surveyor ${a.member}"}",
                )
            }
        }
        _state.update { it.copy(team = TeamResult(label, team, assignments, files), buildings = api.buildings()) }
    }

    /**
     * Stops the team plan under way, as a user's Stop: the walks it has are kept (a member
     * not yet planned gets the systematic walk), saved and written as walk files.
     */
    fun stopPlanning() {
        planning?.stop()
    }

    fun share(file: ShareableFile) = _state.update { it.copy(share = file) }

    fun shared() = _state.update { it.copy(share = null) }

    fun dismissError() = _state.update { it.copy(error = null) }

    /** Shows an error from outside the store (a shared file that could not be read). */
    fun reportError(message: String) = _state.update { it.copy(error = message) }

    private fun progressLine(p: PlanProgress): String =
        p.message + (p.bestUtilityNats?.let { " · team best %.1f nats".format(it) } ?: "")

    private fun busy(block: suspend () -> Unit) = scope.launch { _state.runBusy({ copy(busy = it) }, { copy(error = it) }, block) }
}
