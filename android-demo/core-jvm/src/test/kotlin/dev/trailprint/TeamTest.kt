package dev.trailprint

import dev.trailprint.ffi.PlanAlgorithm
import dev.trailprint.ffi.PlanRequest
import dev.trailprint.ffi.TeamMember
import dev.trailprint.ffi.TeamPlanRequest
import dev.trailprint.ffi.TrailprintException
import dev.trailprint.ffi.TrailprintStore
import dev.trailprint.ffi.WifiReading
import dev.trailprint.ffi.defaultHumanProfile
import dev.trailprint.ffi.defaultRobotProfile
import dev.trailprint.testing.ScratchDir
import dev.trailprint.testing.TestData
import java.io.File
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith
import kotlin.test.assertTrue
import kotlinx.coroutines.runBlocking

/** Issue 9 from the app's side: plan as one of a team, export and merge bundles. */
class TeamTest : ScratchDir("trailprint-team-test") {
    private fun team(store: TrailprintStore, bid: Long, independent: Boolean) = store.planTeam(
        TeamPlanRequest(
            bid,
            listOf(TeamMember("c10", "c10", 30.0), TeamMember("c10", "c10", 30.0)),
            defaultRobotProfile(),
            PlanAlgorithm.GENETIC,
            7uL,
            null,
            independent,
        ),
    )

    @Test
    fun aTeamPlanSavesOnePlanPerMemberAndCollectsMoreThanPlanningAlone() {
        TrailprintStore.openInMemory().use { store ->
            val bid = store.importBuildingJson(TestData.demoBuildingJson, "demo", false).id
            val together = team(store, bid, independent = false)
            val alone = team(store, bid, independent = true)
            assertEquals(2, together.planIds.size)
            assertTrue(
                together.teamUtilityNats > alone.teamUtilityNats,
                "team ${together.teamUtilityNats} vs alone ${alone.teamUtilityNats}",
            )
            // Each member starts a session from their own saved plan.
            val mine = store.getPlan(together.planIds[1])
            assertEquals(together.walks[1], mine.walk)
            store.startSession(mine.id, defaultHumanProfile(), null).close()
        }
    }

    @Test
    fun bundlesMergeOnceAndACorruptBundleImportsNothing() = runBlocking {
        val phone = Trailprint.open(File(dir, "phone.db").path)
        val bid = phone.importBuilding(TestData.demoBuildingJson, "demo")
        val plan = phone.store.newPlan(
            PlanRequest(bid.id, "c00", "c06", 9.0, defaultHumanProfile(), PlanAlgorithm.GREEDY, 1uL, null),
        ).use { it.run(null) }
        val s = phone.startSession(plan.id, defaultHumanProfile())
        var t = 1_700_000_000_000L
        s.checkIn(t, "c00")
        repeat(3) { i -> t += 4000; s.scan(t, listOf(WifiReading("aa:aa", -50.0 - i))) }
        s.close()
        val bundle = phone.exportBundle(bid.id, device = "phone-1", surveyorName = "Ann")
        phone.close()

        val desk = Trailprint.open(File(dir, "desk.db").path)
        val first = desk.importBundle(bundle, "phone-1.json")
        assertTrue(first.buildingCreated)
        assertEquals(1uL, first.sessionsAdded)
        val again = desk.importBundle(bundle, "phone-1.json")
        assertEquals(0uL, again.sessionsAdded)
        assertEquals(0uL, again.eventsAdded)
        val corrupt = bundle.replaceFirst("-51.0", "-15.0")
        val e = assertFailsWith<TrailprintException.InvalidBuilding> { desk.importBundle(corrupt, "bad.json") }
        assertTrue("checksum mismatch" in e.message!!, e.message)
        val truncated = assertFailsWith<TrailprintException.InvalidBuilding> { desk.importBundle(bundle.take(bundle.length / 2), "half.json") }
        assertTrue("truncated" in truncated.message!!, truncated.message)
        assertEquals(1, desk.sessions(desk.buildings().single().id).size)
        desk.close()
    }
}
