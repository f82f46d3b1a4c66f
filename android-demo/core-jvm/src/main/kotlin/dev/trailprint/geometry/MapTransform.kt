package dev.trailprint.geometry

import kotlin.math.hypot
import kotlin.math.min

/** A point in building coordinates, metres (x east, y north). */
data class WorldPoint(val x: Double, val y: Double)

/** A point on screen, pixels (x right, y down). */
data class ScreenPoint(val x: Double, val y: Double)

/** An axis-aligned box in world coordinates. */
data class WorldBounds(val minX: Double, val minY: Double, val maxX: Double, val maxY: Double) {
    val width: Double get() = maxX - minX
    val height: Double get() = maxY - minY

    companion object {
        /** The bounding box of [points]; throws on an empty list. */
        fun of(points: Iterable<WorldPoint>): WorldBounds {
            val it = points.iterator()
            require(it.hasNext()) { "no points to bound" }
            val p0 = it.next()
            var b = WorldBounds(p0.x, p0.y, p0.x, p0.y)
            for (p in it) b = WorldBounds(min(b.minX, p.x), min(b.minY, p.y), maxOf(b.maxX, p.x), maxOf(b.maxY, p.y))
            return b
        }
    }
}

/**
 * World → screen: uniform scale (pixels per metre), y flipped so that north is up, and an
 * offset. [fit] chooses scale and offset so that a world box fills a view with padding,
 * centred on the axis with room to spare.
 */
data class MapTransform(val scale: Double, val offsetX: Double, val offsetY: Double) {
    init {
        require(scale > 0 && scale.isFinite()) { "scale must be positive and finite, got $scale" }
    }

    fun toScreen(p: WorldPoint): ScreenPoint = ScreenPoint(offsetX + p.x * scale, offsetY - p.y * scale)

    fun toWorld(p: ScreenPoint): WorldPoint = WorldPoint((p.x - offsetX) / scale, (offsetY - p.y) / scale)

    /** Zoom by [factor] keeping the screen point [focus] fixed (pinch zoom). */
    fun zoomed(factor: Double, focus: ScreenPoint): MapTransform {
        require(factor > 0) { "zoom factor must be positive, got $factor" }
        val w = toWorld(focus)
        val s = scale * factor
        return MapTransform(s, focus.x - w.x * s, focus.y + w.y * s)
    }

    /** Move by a screen distance (drag). */
    fun panned(dx: Double, dy: Double): MapTransform = copy(offsetX = offsetX + dx, offsetY = offsetY + dy)

    companion object {
        /**
         * Fits [bounds] into a view of [viewWidth] x [viewHeight] pixels with [padding]
         * pixels on every side. A degenerate box (one point, or a line) is given a minimum
         * extent of [minExtent] metres so the scale stays finite.
         */
        fun fit(bounds: WorldBounds, viewWidth: Double, viewHeight: Double, padding: Double = 16.0, minExtent: Double = 1.0): MapTransform {
            require(viewWidth > 2 * padding && viewHeight > 2 * padding) {
                "view ${viewWidth}x$viewHeight is too small for padding $padding"
            }
            val w = maxOf(bounds.width, minExtent)
            val h = maxOf(bounds.height, minExtent)
            val scale = min((viewWidth - 2 * padding) / w, (viewHeight - 2 * padding) / h)
            val cx = (bounds.minX + bounds.maxX) / 2
            val cy = (bounds.minY + bounds.maxY) / 2
            return MapTransform(scale, viewWidth / 2 - cx * scale, viewHeight / 2 + cy * scale)
        }
    }
}

/** Plane geometry helpers for guidance and hit tests. */
object Geometry {
    fun distance(a: WorldPoint, b: WorldPoint): Double = hypot(a.x - b.x, a.y - b.y)

    /** Index of the point of [points] nearest to [p] within [maxDistance], or null. */
    fun nearest(points: List<WorldPoint>, p: WorldPoint, maxDistance: Double = Double.POSITIVE_INFINITY): Int? {
        var best: Int? = null
        var bestD = maxDistance
        for ((i, q) in points.withIndex()) {
            val d = distance(p, q)
            if (d <= bestD) { best = i; bestD = d }
        }
        return best
    }

    /** The point [fraction] of the way from [a] to [b]. */
    fun lerp(a: WorldPoint, b: WorldPoint, fraction: Double): WorldPoint =
        WorldPoint(a.x + (b.x - a.x) * fraction, a.y + (b.y - a.y) * fraction)

    /**
     * The point at arc length [s] along the polyline [points] (clamped to its ends).
     */
    fun pointAlong(points: List<WorldPoint>, s: Double): WorldPoint {
        require(points.isNotEmpty()) { "empty polyline" }
        if (s <= 0) return points.first()
        var left = s
        for (i in 1 until points.size) {
            val d = distance(points[i - 1], points[i])
            if (left <= d && d > 0) return lerp(points[i - 1], points[i], left / d)
            left -= d
        }
        return points.last()
    }

    /** Total length of a polyline. */
    fun length(points: List<WorldPoint>): Double = points.zipWithNext { a, b -> distance(a, b) }.sum()
}
