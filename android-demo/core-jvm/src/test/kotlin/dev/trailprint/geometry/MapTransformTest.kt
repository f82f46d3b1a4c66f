package dev.trailprint.geometry

import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertNull
import kotlin.test.assertTrue

class MapTransformTest {
    private val corridor = WorldBounds(0.0, -6.0, 30.0, 10.5)

    @Test
    fun fitKeepsTheWholeBoxInsideThePaddedViewAndCentresIt() {
        val t = MapTransform.fit(corridor, 1080.0, 1920.0, padding = 40.0)
        val corners = listOf(WorldPoint(0.0, -6.0), WorldPoint(30.0, 10.5), WorldPoint(0.0, 10.5), WorldPoint(30.0, -6.0))
        for (c in corners) {
            val s = t.toScreen(c)
            assertTrue(s.x >= 40.0 - 1e-9 && s.x <= 1040.0 + 1e-9 && s.y >= 40.0 - 1e-9 && s.y <= 1880.0 + 1e-9, "$c -> $s")
        }
        // Width is the binding dimension: 1000 px for 30 m.
        assertEquals(1000.0 / 30.0, t.scale, 1e-12)
        val centre = t.toScreen(WorldPoint(15.0, 2.25))
        assertEquals(540.0, centre.x, 1e-9)
        assertEquals(960.0, centre.y, 1e-9)
    }

    @Test
    fun northIsUpAndToWorldInvertsToScreen() {
        val t = MapTransform.fit(corridor, 800.0, 600.0)
        val lo = t.toScreen(WorldPoint(5.0, 0.0))
        val hi = t.toScreen(WorldPoint(5.0, 5.0))
        assertTrue(hi.y < lo.y, "larger y must be higher on screen")
        val p = WorldPoint(12.3, -4.5)
        val back = t.toWorld(t.toScreen(p))
        assertEquals(p.x, back.x, 1e-9)
        assertEquals(p.y, back.y, 1e-9)
    }

    @Test
    fun zoomKeepsTheFocusPointFixed() {
        val t = MapTransform.fit(corridor, 800.0, 600.0)
        val focus = ScreenPoint(200.0, 300.0)
        val w = t.toWorld(focus)
        val z = t.zoomed(2.5, focus)
        val again = z.toScreen(w)
        assertEquals(focus.x, again.x, 1e-9)
        assertEquals(focus.y, again.y, 1e-9)
        assertEquals(t.scale * 2.5, z.scale, 1e-12)
    }

    @Test
    fun aSinglePointStillGetsAFiniteScale() {
        val t = MapTransform.fit(WorldBounds.of(listOf(WorldPoint(3.0, 4.0))), 100.0, 100.0, padding = 10.0, minExtent = 2.0)
        assertEquals(40.0, t.scale, 1e-12)
        assertEquals(50.0, t.toScreen(WorldPoint(3.0, 4.0)).x, 1e-9)
    }

    @Test
    fun nearestAndPointAlong() {
        val pts = listOf(WorldPoint(0.0, 0.0), WorldPoint(3.0, 0.0), WorldPoint(3.0, 4.0))
        assertEquals(1, Geometry.nearest(pts, WorldPoint(2.6, 0.3)))
        assertNull(Geometry.nearest(pts, WorldPoint(10.0, 10.0), maxDistance = 1.0))
        assertEquals(7.0, Geometry.length(pts), 1e-12)
        val p = Geometry.pointAlong(pts, 5.0)
        assertEquals(3.0, p.x, 1e-12)
        assertEquals(2.0, p.y, 1e-12)
        assertEquals(pts.last(), Geometry.pointAlong(pts, 100.0))
    }
}
