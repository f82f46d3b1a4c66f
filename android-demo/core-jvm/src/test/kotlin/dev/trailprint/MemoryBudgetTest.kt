package dev.trailprint

import dev.trailprint.demo.SimulatedWifi
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
import dev.trailprint.ffi.WifiReading
import dev.trailprint.ffi.defaultRobotProfile
import dev.trailprint.ffi.defaultSessionOptions
import dev.trailprint.robot.SimulatedRobot
import dev.trailprint.robot.SimulatedRobotConfig
import dev.trailprint.robot.Waypoint
import dev.trailprint.testing.TestData
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

    @Test
    fun theBudgetIsAnEighthOfTheRamAtMostTheEnginesDefaultAndAtLeast64MiB() {
        assertEquals(256uL, DeviceMemory.budgetMb(2 * gib, lowRam = false))
        assertEquals(384uL, DeviceMemory.budgetMb(3 * gib, lowRam = false))
        assertEquals(512uL, DeviceMemory.budgetMb(4 * gib, lowRam = false))
        assertEquals(512uL, DeviceMemory.budgetMb(8 * gib, lowRam = false))
        assertEquals(512uL, DeviceMemory.budgetMb(64 * gib, lowRam = false))
        // totalMem is what the kernel has, a little under the advertised size.
        assertEquals(240uL, DeviceMemory.budgetMb(1920 * mib, lowRam = false))
        assertEquals(64uL, DeviceMemory.budgetMb(512 * mib, lowRam = false))
        assertEquals(64uL, DeviceMemory.budgetMb(0, lowRam = false))
        assertEquals(64uL, DeviceMemory.budgetMb(-1, lowRam = false))
    }

    @Test
    fun aLowRamDeviceGetsASixteenthAtLeast64MiB() {
        assertEquals(64uL, DeviceMemory.budgetMb(1 * gib, lowRam = true))
        assertEquals(64uL, DeviceMemory.budgetMb(512 * mib, lowRam = true))
        assertEquals(128uL, DeviceMemory.budgetMb(2 * gib, lowRam = true))
        assertEquals(512uL, DeviceMemory.budgetMb(16 * gib, lowRam = true))
    }

    /** Drives a simulated robot along [plan] with 640 scans, then finishes and closes [session]. */
    private fun drive(session: SurveySession, map: BuildingMap, plan: PlanSummary): SessionSummary = session.use { s ->
        val byId = map.vertices.associateBy { it.id }
        val waypoints = plan.walk.map { id -> byId.getValue(id).let { Waypoint(id, it.x, it.y, it.floor) } }
        val wifi = SimulatedWifi(map, seed = 2)
        val t0 = 1_700_000_000_000L
        val robot = SimulatedRobot(SimulatedRobotConfig(speed = plan.lengthM / 640, poseIntervalMs = 1000, seed = 2, timeScale = 0.0, startTimeMs = t0))
        var t = t0
        var lastScan: Long? = null
        for (p in robot.trajectory(waypoints)) {
            t = p.timestampMs
            s.robotPose(t, p.x, p.y, p.floor)
            if (lastScan == null || t - lastScan >= 1000) {
                lastScan = t
                s.scan(t, wifi.scanAt(t, p.x, p.y, p.floor).readings.map { WifiReading(it.bssid, it.rssDbm.toDouble()) })
            }
        }
        s.finish(t + 1000)
    }

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
