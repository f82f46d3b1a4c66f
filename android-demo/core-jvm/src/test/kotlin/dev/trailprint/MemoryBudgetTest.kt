package dev.trailprint

import dev.trailprint.ffi.BuildingMap
import dev.trailprint.ffi.PlanAlgorithm
import dev.trailprint.ffi.PlanRequest
import dev.trailprint.ffi.PlanSummary
import dev.trailprint.ffi.SessionSummary
import dev.trailprint.ffi.SurveySession
import dev.trailprint.ffi.TeamMember
import dev.trailprint.ffi.TeamPlanRequest
import dev.trailprint.ffi.TrailprintException
import dev.trailprint.ffi.TrailprintStore
import dev.trailprint.ffi.defaultRobotProfile
import dev.trailprint.ffi.defaultSessionOptions
import dev.trailprint.testing.TestData
import dev.trailprint.testing.driveRobotAlong
import dev.trailprint.testing.greedyPlan
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith
import kotlin.test.assertIs
import kotlin.test.assertTrue
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.flow.toList
import kotlinx.coroutines.runBlocking
import kotlinx.coroutines.withTimeout

/** The memory budget the app gives the engine: from the phone's RAM, in every request. */
class MemoryBudgetTest {
    private val gib = 1L shl 30
    private val mib = 1L shl 20

    /**
     * An eighth of the RAM, at most the engine's default (512 MiB) and at least 64 MiB; a
     * sixteenth on a low-RAM device. Rows: RAM in bytes, low-RAM flag, budget in MiB.
     */
    @Test
    fun theBudgetIsAnEighthOfTheRamOrASixteenthOnALowRamDeviceFrom64To512MiB() {
        val rows = listOf(
            Triple(2 * gib, false, 256uL),
            Triple(3 * gib, false, 384uL),
            Triple(4 * gib, false, 512uL),
            Triple(8 * gib, false, 512uL),
            Triple(64 * gib, false, 512uL),
            // totalMem is what the kernel has, a little under the advertised size.
            Triple(1920 * mib, false, 240uL),
            Triple(512 * mib, false, 64uL),
            Triple(0L, false, 64uL),
            Triple(-1L, false, 64uL),
            Triple(1 * gib, true, 64uL),
            Triple(512 * mib, true, 64uL),
            Triple(2 * gib, true, 128uL),
            Triple(16 * gib, true, 512uL),
        )
        for ((ram, lowRam, want) in rows) {
            assertEquals(want, DeviceMemory.budgetMb(ram, lowRam), "RAM $ram bytes, low-RAM $lowRam")
        }
    }

    /** Drives a simulated robot along [plan] with 640 scans, then finishes and closes [session]. */
    private fun drive(session: SurveySession, map: BuildingMap, plan: PlanSummary): SessionSummary =
        session.use { it.driveRobotAlong(map, plan.walk, plan.lengthM, 640) }

    @Test
    fun aTrailprintWithTheDevicesBudgetPassesItToPlansTeamPlansAndSessions() = runBlocking {
        TrailprintStore.openInMemory().use { store ->
            // Two faces of one database: the library's default budget, and a phone allowing 1 MiB.
            val desk = Trailprint(store, Dispatchers.IO)
            val phone = Trailprint(store, Dispatchers.IO, memoryBudgetMb = 1uL)
            val bid = desk.importBuilding(TestData.demoBuildingJson, "demo").id
            // As the plan screen builds it: no budget of its own.
            val request = PlanRequest(bid, "c00", "c20", 50.0, defaultRobotProfile(), PlanAlgorithm.GREEDY, 1uL, null)
            fun assertOneMiB(e: Exception) = assertTrue("more than the memory budget of 1 MiB" in e.message!!, e.message)

            assertOneMiB(assertFailsWith<TrailprintException.InvalidRequest> { withTimeout(60_000) { phone.plan(request).toList() } })
            val plan = assertIs<PlanEvent.Done>(withTimeout(60_000) { desk.plan(request).toList() }.last()).plan
            assertEquals("c20", plan.walk.last())
            // A budget the request names itself wins.
            assertIs<PlanEvent.Done>(withTimeout(60_000) { phone.plan(request.copy(memoryBudgetMb = 512uL)).toList() }.last())

            val team = TeamPlanRequest(bid, listOf(TeamMember("c00", "c00", 30.0)), defaultRobotProfile(), PlanAlgorithm.GREEDY, 1uL, null, false)
            assertOneMiB(assertFailsWith<TrailprintException.InvalidRequest> { phone.planTeam(team) })
            assertOneMiB(assertFailsWith<TrailprintException.InvalidRequest> { withTimeout(60_000) { phone.startTeamPlan(team).events.toList() } })
            assertEquals(1, desk.planTeam(team).planIds.size)

            // A session's running figures keep to half its budget: the phone's, when the caller names none.
            // A robot walk to the far end, 640 scans: more than half of 1 MiB holds exactly (as in SessionTest).
            val far = store.greedyPlan(bid, end = "r34", budget = 300.0, profile = defaultRobotProfile())
            val map = desk.map(bid)
            assertTrue(drive(phone.startSession(far.id, defaultRobotProfile()), map, far).sampleBlock > 1uL)
            val filledIn = phone.startSession(far.id, defaultRobotProfile(), defaultSessionOptions().copy(memoryBudgetMb = null))
            assertTrue(drive(filledIn, map, far).sampleBlock > 1uL)
            val named = phone.startSession(far.id, defaultRobotProfile(), defaultSessionOptions().copy(memoryBudgetMb = 512uL))
            assertEquals(1uL, drive(named, map, far).sampleBlock)
            assertEquals(1uL, drive(desk.startSession(far.id, defaultRobotProfile()), map, far).sampleBlock)
        }
    }
}
