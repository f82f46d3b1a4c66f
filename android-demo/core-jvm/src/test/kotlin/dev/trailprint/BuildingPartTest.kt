package dev.trailprint

import dev.trailprint.ffi.PlanAlgorithm
import dev.trailprint.ffi.PlanRequest
import dev.trailprint.ffi.TeamMember
import dev.trailprint.ffi.TeamPlanRequest
import dev.trailprint.ffi.TrailprintException
import dev.trailprint.ffi.TrailprintStore
import dev.trailprint.ffi.defaultRobotProfile
import dev.trailprint.ui.PartSuggestion
import dev.trailprint.ui.PlanModel
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith
import kotlin.test.assertNull
import kotlin.test.assertTrue
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.flow.first
import kotlinx.coroutines.runBlocking
import kotlinx.coroutines.withTimeout

/** A building too large for the phone's memory is planned by parts, as the refusal says. */
class BuildingPartTest {
    /** A straight corridor of [n] vertices 1 m apart (v0, v1, ...), the kernel in the file. */
    private fun corridor(n: Int): String {
        val vertices = (0 until n).joinToString(",") { """{"id":"v$it","x":$it,"y":0}""" }
        val edges = (1 until n).joinToString(",") { """{"a":"v${it - 1}","b":"v$it"}""" }
        return """{"format":"survey-building/1","name":"Long corridor","vertices":[$vertices],""" +
            """"edges":[$edges],"kernel":{"sf2":40,"ell":6,"sn2":9}}"""
    }

    private fun request(buildingId: Long) =
        PlanRequest(buildingId, "v0", "v0", 60.0, defaultRobotProfile(), PlanAlgorithm.AUTO, 1uL, 1.0, 64uL)

    @Test
    fun aBuildingRefusedForMemoryIsPlannedOnThePartTheRefusalNames() {
        TrailprintStore.openInMemory().use { store ->
            val whole = store.importBuildingJson(corridor(3000), "corridor.json", false)
            val refused = assertFailsWith<TrailprintException.InvalidRequest> {
                store.newPlan(request(whole.id)).use { it.run(null) }
            }
            val message = refused.message!!
            assertTrue("more than the memory budget of 64 MiB" in message, message)
            assertTrue("--around v0 --radius 42" in message, message)

            val part = store.importBuildingPart(whole.id, emptyList(), "v0", 42.0, null, false)
            assertEquals("Long corridor (within 42 m of v0)", part.name)
            assertEquals(43uL, part.vertices)
            assertEquals("part of \"Long corridor\"", part.source)
            val plan = store.newPlan(request(part.id)).use { it.run(null) }
            assertTrue(plan.lengthM > 0.95 * 60.0 && plan.lengthM <= 60.0 + 1e-9, "${plan.lengthM}")
            assertTrue(plan.utilityNats > 0.0)
        }
    }

    @Test
    fun thePlanScreenOffersThePartARefusalNamesAndImportsItOnce() = runBlocking {
        Trailprint.inMemory(Dispatchers.IO).use { api ->
            // 8,000 vertices: the shortest-path table alone is 768 MB, over the 512 MiB default.
            val bid = api.importBuilding(corridor(8000), "corridor.json").id
            val model = PlanModel(api, this, bid)
            model.load().join()
            model.tapVertex("v0")
            model.tapVertex("v0")
            model.setBudget(60.0)
            model.plan()
            val refused = withTimeout(60_000) { model.state.first { !it.planning && it.error != null } }
            // A 60 m round trip reaches 30 m; two length scales (6 m) more.
            assertEquals(PartSuggestion("v0", 42.0), refused.suggestedPart, refused.error)
            model.planSuggestedPart()
            val opened = withTimeout(60_000) { model.state.first { it.partBuilding != null || it.error != null } }
            assertNull(opened.error)
            assertNull(opened.suggestedPart)
            val part = opened.partBuilding!!
            assertEquals(43uL, part.vertices)
            // The same part again (the refusal seen a second time): the building imported before.
            assertEquals(part.id, api.importBuildingPart(bid, around = "v0", radiusM = 42.0).id)
            assertEquals(2, api.buildings().size)
            // Opened: forgotten, so that going back to the whole building does not open it again.
            model.partOpened()
            assertNull(model.state.value.partBuilding)
        }
    }

    @Test
    fun aTeamPlanTakesThePhonesMemoryBudgetToo() {
        TrailprintStore.openInMemory().use { store ->
            val whole = store.importBuildingJson(corridor(3000), "corridor.json", false)
            val members = listOf(TeamMember("v0", "v0", 30.0), TeamMember("v20", "v20", 30.0))
            fun team(bid: Long) = store.planTeam(
                TeamPlanRequest(bid, members, defaultRobotProfile(), PlanAlgorithm.COVERAGE, 1uL, null, false, 64uL),
            )
            val refused = assertFailsWith<TrailprintException.InvalidRequest> { team(whole.id) }
            assertTrue("more than the memory budget of 64 MiB" in refused.message!!, refused.message)
            val part = store.importBuildingPart(whole.id, emptyList(), "v0", 80.0, null, false)
            assertEquals(2, team(part.id).planIds.size)
        }
    }

    @Test
    fun aBadPartIsRefusedByNameAndImportsNothing() {
        TrailprintStore.openInMemory().use { store ->
            val whole = store.importBuildingJson(corridor(50), "corridor.json", false)
            val noFloor = assertFailsWith<TrailprintException.InvalidRequest> {
                store.importBuildingPart(whole.id, listOf(3L), null, null, null, false)
            }
            assertTrue("no floor 3" in noFloor.message!!, noFloor.message)
            val noVertex = assertFailsWith<TrailprintException.InvalidRequest> {
                store.importBuildingPart(whole.id, emptyList(), "w9", 10.0, null, false)
            }
            assertTrue("unknown vertex \"w9\"" in noVertex.message!!, noVertex.message)
            val halfAsked = assertFailsWith<TrailprintException.InvalidRequest> {
                store.importBuildingPart(whole.id, emptyList(), "v0", null, null, false)
            }
            assertTrue("both the vertex and the radius" in halfAsked.message!!, halfAsked.message)
            assertEquals(listOf("Long corridor"), store.listBuildings().map { it.name })
        }
    }
}
