package dev.trailprint.team

import dev.trailprint.AppException
import dev.trailprint.Trailprint
import dev.trailprint.ffi.BundleImportSummary
import dev.trailprint.ffi.PlanSummary
import dev.trailprint.json.Json
import dev.trailprint.json.JsonException
import kotlinx.coroutines.CoroutineDispatcher
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.withContext

/** The walk one surveyor of a team is asked to take, as the header of a walk file. */
data class WalkAssignment(
    /** The team planning this walk belongs to (shown to the surveyor). */
    val team: String,
    /** 1-based position of this surveyor in the team. */
    val member: Int,
    val members: Int,
    val surveyorName: String?,
    val building: String,
    val start: String,
    val end: String,
    val budgetM: Double,
    val walk: List<String>,
    val lengthM: Double,
    val utilityNats: Double,
)

/** A walk file opened on a surveyor's phone: the plan to walk, saved in its database. */
data class ReceivedWalk(
    val assignment: WalkAssignment,
    val buildingId: Long,
    val plan: PlanSummary,
    /** What importing the file's bundle added (the building, the team's sessions so far). */
    val imported: BundleImportSummary,
)

/**
 * Walk files (`trailprint-walk/1`): how a coordinator's phone hands each surveyor of a team
 * the walk planned for them, offline, as one file shared like any other.
 *
 * A walk file is JSON: `{"format": "trailprint-walk/1", "assignment": {...}, "bundle": "..."}`.
 * The assignment says which walk it is (team, member k of N, building, start, end, budget,
 * the vertex ids). The bundle — the coordinator's survey bundle of the building, as a JSON
 * string — carries the building and the saved plan: bundles carry the plans their
 * sessions used, so the coordinator starts a session on each member's plan and aborts it
 * at once ("carrier" sessions, with no events but start and abort), and the surveyor's
 * phone gets the plan by importing the bundle. It also gets every session the coordinator
 * merged, so the surveyor's replanning on the way conditions on what the team has
 * collected. Importing is idempotent, like any bundle.
 *
 * (The bindings have no call that saves a plan record from a file; with one, the bundle
 * would only be needed for the building.)
 */
object WalkFiles {
    const val FORMAT = "trailprint-walk/1"

    /** The text of a walk file. */
    fun encode(a: WalkAssignment, bundleJson: String): String = Json.encode(
        linkedMapOf(
            "format" to FORMAT,
            "assignment" to linkedMapOf(
                "team" to a.team,
                "member" to a.member,
                "members" to a.members,
                "surveyor_name" to a.surveyorName,
                "building" to a.building,
                "start" to a.start,
                "end" to a.end,
                "budget_m" to a.budgetM,
                "walk" to a.walk,
                "length_m" to a.lengthM,
                "utility_nats" to a.utilityNats,
            ),
            "bundle" to bundleJson,
        ),
    ) + "\n"

    /** Parses a walk file; [origin] (its name) prefixes every error, with the field. */
    fun decode(text: String, origin: String): Pair<WalkAssignment, String> {
        val doc = try {
            Json.parse(text)
        } catch (e: JsonException) {
            throw AppException("$origin: not a walk file (${e.message})", e)
        }
        val o = doc as? Map<*, *> ?: throw AppException("$origin: not a walk file (expected a JSON object)")
        if (o["format"] != FORMAT) {
            throw AppException("$origin: field format: expected \"$FORMAT\", got ${describe(o["format"])}")
        }
        val a = o["assignment"] as? Map<*, *> ?: throw AppException("$origin: field assignment: expected an object, got ${describe(o["assignment"])}")
        fun bad(field: String, what: String): Nothing = throw AppException("$origin: field assignment.$field: $what, got ${describe(a[field])}")
        fun str(field: String): String = a[field] as? String ?: bad(field, "expected a string")
        fun num(field: String): Double = (a[field] as? Double)?.takeIf { it.isFinite() } ?: bad(field, "expected a number")
        fun int(field: String): Int = num(field).let { if (it != Math.rint(it) || it < 1 || it > 1000) bad(field, "expected a whole number from 1 to 1000") else it.toInt() }
        val walk = (a["walk"] as? List<*>)?.map { it as? String ?: bad("walk", "expected vertex ids (strings)") } ?: bad("walk", "expected a list of vertex ids")
        if (walk.isEmpty()) bad("walk", "expected at least one vertex")
        val member = int("member")
        val members = int("members")
        if (member > members) bad("member", "expected at most members = $members")
        val name = a["surveyor_name"]
        if (name != null && name !is String) bad("surveyor_name", "expected a string or null")
        val budget = num("budget_m")
        if (budget <= 0) bad("budget_m", "expected a positive number of metres")
        val assignment = WalkAssignment(
            team = str("team"), member = member, members = members, surveyorName = name as String?,
            building = str("building"), start = str("start"), end = str("end"), budgetM = budget,
            walk = walk, lengthM = num("length_m"), utilityNats = num("utility_nats"),
        )
        if (walk.first() != assignment.start || walk.last() != assignment.end) {
            bad("walk", "expected a walk from start ${assignment.start} to end ${assignment.end}")
        }
        val bundle = o["bundle"] as? String ?: throw AppException("$origin: field bundle: expected the bundle as a JSON string, got ${describe(o["bundle"])}")
        return assignment to bundle
    }

    /**
     * Opens a walk file on a surveyor's phone: imports its bundle (building, plan, the
     * team's sessions) and finds the saved plan of the walk. A file that does not parse,
     * or whose bundle is corrupt, changes nothing.
     */
    suspend fun open(api: Trailprint, text: String, origin: String, io: CoroutineDispatcher = Dispatchers.IO): ReceivedWalk {
        val (a, bundle) = decode(text, origin)
        val imported = api.importBundle(bundle, "$origin: bundle")
        if (imported.building != a.building) {
            throw AppException("$origin: field assignment.building: the bundle is of building \"${imported.building}\", not \"${a.building}\"")
        }
        return withContext(io) {
            val building = api.store.listBuildings().firstOrNull { it.name == a.building }
                ?: throw AppException("$origin: building \"${a.building}\" is not in the database after the import")
            val plan = api.store.listPlans(building.id).lastOrNull { it.walk == a.walk && it.start == a.start && it.end == a.end && it.budgetM == a.budgetM }
                ?: throw AppException("$origin: the bundle carries no plan of the walk ${a.walk.joinToString(" → ")} (was it made by a Trailprint coordinator?)")
            ReceivedWalk(a, building.id, plan, imported)
        }
    }

    private fun describe(v: Any?): String = try {
        Json.encode(v).let { if (it.length > 60) it.take(57) + "..." else it }
    } catch (e: JsonException) {
        v.toString()
    }

    /** Whether [text] looks like a walk file rather than a bundle (for an incoming share). */
    fun looksLikeWalkFile(text: String): Boolean = text.take(200).contains("\"$FORMAT\"")
}
