package dev.trailprint.app.ui

import androidx.compose.foundation.Canvas
import androidx.compose.foundation.gestures.detectTapGestures
import androidx.compose.runtime.Composable
import androidx.compose.runtime.getValue
import androidx.compose.runtime.mutableStateOf
import androidx.compose.runtime.remember
import androidx.compose.runtime.setValue
import androidx.compose.ui.Modifier
import androidx.compose.ui.geometry.Offset
import androidx.compose.ui.graphics.Color
import androidx.compose.ui.graphics.Path
import androidx.compose.ui.graphics.drawscope.Stroke
import androidx.compose.ui.input.pointer.pointerInput
import androidx.compose.ui.layout.onSizeChanged
import dev.trailprint.ffi.BuildingMap
import dev.trailprint.geometry.Geometry
import dev.trailprint.geometry.MapTransform
import dev.trailprint.geometry.ScreenPoint
import dev.trailprint.geometry.WorldBounds
import dev.trailprint.geometry.WorldPoint

/** What to draw over the building (all optional). */
data class MapOverlay(
    val planned: List<WorldPoint> = emptyList(),
    val walked: List<WorldPoint> = emptyList(),
    val estimate: WorldPoint? = null,
    val next: WorldPoint? = null,
    val highlighted: Set<String> = emptySet(),
)

/**
 * The building drawn to fit the view (world → screen by the host-tested [MapTransform]):
 * edges, vertices, the planned walk, the walked part, the estimate and the next waypoint.
 * A tap reports the nearest vertex within 40 px.
 */
@Composable
fun MapCanvas(map: BuildingMap, overlay: MapOverlay, modifier: Modifier = Modifier, floor: Long = 0, onVertexTap: ((String) -> Unit)? = null) {
    var transform by remember(map) { mutableStateOf<MapTransform?>(null) }
    val vertices = map.vertices.filter { it.floor == floor }
    val points = vertices.map { WorldPoint(it.x, it.y) }
    val index = map.vertices.associateBy { it.id }
    Canvas(
        modifier
            .onSizeChanged { size ->
                if (points.isNotEmpty() && size.width > 100 && size.height > 100) {
                    transform = MapTransform.fit(WorldBounds.of(points), size.width.toDouble(), size.height.toDouble(), padding = 40.0)
                }
            }
            .pointerInput(map, onVertexTap) {
                detectTapGestures { tap ->
                    val t = transform ?: return@detectTapGestures
                    val w = t.toWorld(ScreenPoint(tap.x.toDouble(), tap.y.toDouble()))
                    Geometry.nearest(points, w, maxDistance = 40.0 / t.scale)?.let { onVertexTap?.invoke(vertices[it].id) }
                }
            },
    ) {
        val t = transform ?: return@Canvas
        fun off(p: WorldPoint): Offset = t.toScreen(p).let { Offset(it.x.toFloat(), it.y.toFloat()) }
        for (e in map.edges) {
            val a = index[e.a] ?: continue
            val b = index[e.b] ?: continue
            if (a.floor != floor || b.floor != floor) continue
            drawLine(Color.LightGray, off(WorldPoint(a.x, a.y)), off(WorldPoint(b.x, b.y)), strokeWidth = 6f)
        }
        fun polyline(pts: List<WorldPoint>, color: Color, width: Float) {
            if (pts.size < 2) return
            val path = Path()
            pts.forEachIndexed { i, p -> off(p).let { if (i == 0) path.moveTo(it.x, it.y) else path.lineTo(it.x, it.y) } }
            drawPath(path, color, style = Stroke(width))
        }
        polyline(overlay.planned, Color(0xFF1E88E5), 10f)
        polyline(overlay.walked, Color(0xFF43A047), 8f)
        for (v in vertices) {
            val c = if (v.id in overlay.highlighted) Color(0xFFE53935) else Color.DarkGray
            drawCircle(c, radius = if (v.id in overlay.highlighted) 14f else 6f, center = off(WorldPoint(v.x, v.y)))
        }
        overlay.next?.let { drawCircle(Color(0xFFFB8C00), radius = 18f, center = off(it), style = Stroke(6f)) }
        overlay.estimate?.let { drawCircle(Color(0xFF8E24AA), radius = 12f, center = off(it)) }
    }
}
