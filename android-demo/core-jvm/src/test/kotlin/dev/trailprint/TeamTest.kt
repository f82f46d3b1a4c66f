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
import kotlin.test.assertIs
import kotlin.test.assertTrue
import kotlinx.coroutines.CompletableDeferred
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.async
import kotlinx.coroutines.flow.onEach
import kotlinx.coroutines.flow.toList
import kotlinx.coroutines.runBlocking
import kotlinx.coroutines.withTimeout

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
    fun stoppingATeamPlanKeepsAWalkForEveryMemberAndSavesThem() = runBlocking {
        Trailprint.inMemory(Dispatchers.IO).use { api ->
            val bid = api.importBuilding(TestData.demoBuildingJson, "demo").id
            val members = listOf(TeamMember("c00", "c00", 300.0), TeamMember("c10", "c10", 300.0))
            // Branch and bound on 300 m: hours without the stop.
            val running = api.startTeamPlan(
                TeamPlanRequest(bid, members, defaultRobotProfile(), PlanAlgorithm.EXACT, 1uL, null, false),
            )
            // Stop once the first member's planner has reported a best walk.
            val best = CompletableDeferred<Unit>()
            val events = async(Dispatchers.Default) {
                running.events.onEach {
                    if (it is TeamPlanEvent.Progress && it.progress.bestUtilityNats != null) best.complete(Unit)
                }.toList()
            }
            withTimeout(60_000) { best.await() }
            running.stop()
            val all = withTimeout(30_000) { events.await() }
            val team = assertIs<TeamPlanEvent.Done>(all.last()).team
            assertTrue(team.cancelled)
            assertEquals(listOf("cancelled", "cancelled"), team.terminations)
            assertEquals(2, team.planIds.size)
            members.forEachIndexed { i, m ->
                val plan = api.plan(team.planIds[i])
                assertEquals(team.walks[i], plan.walk)
                assertEquals(m.start, plan.walk.first())
                assertEquals(m.end, plan.walk.last())
                assertTrue(plan.lengthM <= m.budgetM + 1e-9 && plan.utilityNats > 0.0, "$plan")
            }
            // The second member, never reached, has the systematic walk: 300 m is more than
            // every edge of this building, which that walk then walks.
            val walked = team.walks[1].zipWithNext { a, b -> setOf(a, b) }.toSet()
            val edges = api.map(bid).edges.map { setOf(it.a, it.b) }.toSet()
            assertEquals(edges, walked)
            val messages = all.filterIsInstance<TeamPlanEvent.Progress>().map { it.progress.message }
            assertTrue(messages.any { it.startsWith("surveyor 1/2, in turn: ") }, "$messages")
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
