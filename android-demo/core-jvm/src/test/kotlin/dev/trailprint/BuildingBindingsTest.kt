package dev.trailprint

import dev.trailprint.ffi.TrailprintException
import dev.trailprint.ffi.parseBuilding
import dev.trailprint.testing.TestData
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith
import kotlin.test.assertTrue

class BuildingBindingsTest {
    @Test
    fun parsesTheDemoBuilding() {
        val map = parseBuilding(TestData.demoBuildingJson, "demo-building.json")
        assertEquals("Demo office", map.name)
        assertEquals(48, map.vertices.size)
        assertEquals(60, map.edges.size)
        assertEquals(10u, map.pilotCount)
        val door = map.edges.single { it.a == "c16" && it.b == "r00" }
        assertEquals(2.5, door.lengthM, 1e-12)
        assertEquals(6.0, map.kernel!!.ell, 0.0)
    }

    @Test
    fun anUnknownEdgeEndIsAnInvalidBuildingNamingTheVertex() {
        val json = TestData.demoBuildingJson.replaceFirst("\"b\": \"c01\"", "\"b\": \"nowhere\"")
        val e = assertFailsWith<TrailprintException.InvalidBuilding> {
            parseBuilding(json, "broken.json")
        }
        val msg = e.message!!
        assertTrue("broken.json" in msg && "edges[0].b" in msg && "nowhere" in msg, msg)
    }

    @Test
    fun textThatIsNotJsonIsAnInvalidBuilding() {
        val e = assertFailsWith<TrailprintException.InvalidBuilding> { parseBuilding("{", "<clipboard>") }
        assertTrue("<clipboard>" in e.message!!, e.message)
    }
}
