package dev.trailprint

import dev.trailprint.ffi.PlanAlgorithm
import dev.trailprint.ffi.PlanRequest
import dev.trailprint.ffi.TrailprintException
import dev.trailprint.ffi.TrailprintStore
import dev.trailprint.ffi.defaultRobotProfile
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith
import kotlin.test.assertTrue

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
            assertTrue("--around v0 --radius 60" in message, message)

            val part = store.importBuildingPart(whole.id, emptyList(), "v0", 60.0, null, false)
            assertEquals("Long corridor (within 60 m of v0)", part.name)
            assertEquals(61uL, part.vertices)
            assertEquals("part of \"Long corridor\"", part.source)
            val plan = store.newPlan(request(part.id)).use { it.run(null) }
            assertTrue(plan.lengthM > 0.95 * 60.0 && plan.lengthM <= 60.0 + 1e-9, "${plan.lengthM}")
            assertTrue(plan.utilityNats > 0.0)
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
