package dev.trailprint.demo

import dev.trailprint.ffi.BuildingMap
import dev.trailprint.sensors.WifiReading
import dev.trailprint.sensors.WifiScan
import dev.trailprint.sensors.WifiScanSource
import java.util.Random
import kotlin.math.hypot
import kotlin.math.log10
import kotlin.math.roundToInt
import kotlinx.coroutines.channels.Channel
import kotlinx.coroutines.flow.Flow
import kotlinx.coroutines.flow.receiveAsFlow

/**
 * Simulated Wi-Fi for the host demo and tests: access points at every [every]-th vertex
 * of the building, a log-distance path loss with seeded Gaussian noise, readings weaker
 * than -95 dBm not heard. Not a model of any real building.
 */
class SimulatedWifi(map: BuildingMap, seed: Long = 1, every: Int = 8, private val noiseDb: Double = 2.0) {
    private data class Ap(val bssid: String, val x: Double, val y: Double, val floor: Long)

    private val aps = map.vertices.filterIndexed { i, _ -> i % every == 0 }.mapIndexed { i, v ->
        Ap("02:00:00:00:%02x:%02x".format(i / 256, i % 256), v.x, v.y, v.floor)
    }
    private val random = Random(seed)

    /** A scan completed at [tMs] at position ([x], [y]) on [floor]. */
    fun scanAt(tMs: Long, x: Double, y: Double, floor: Long): WifiScan {
        val readings = aps.mapNotNull { ap ->
            val d = maxOf(1.0, hypot(ap.x - x, ap.y - y))
            val wall = if (ap.floor == floor) 0.0 else 15.0
            val rss = -38.0 - 25.0 * log10(d) - wall + random.nextGaussian() * noiseDb
            if (rss < -95.0) null else WifiReading(ap.bssid, rss.roundToInt().coerceIn(-120, 0))
        }
        return WifiScan(tMs, readings)
    }

    /**
     * A [WifiScanSource] that completes each requested scan at once, wherever [where] says
     * the device is, stamped with [clock].
     */
    fun source(clock: () -> Long, where: () -> Triple<Double, Double, Long>): WifiScanSource = object : WifiScanSource {
        private val completed = Channel<WifiScan>(Channel.UNLIMITED)

        override fun results(): Flow<WifiScan> = completed.receiveAsFlow()

        override fun requestScan(): Boolean {
            val (x, y, f) = where()
            return completed.trySend(scanAt(clock(), x, y, f)).isSuccess
        }
    }
}

/** One thing a simulated surveyor does. */
sealed interface WalkEvent {
    val tMs: Long
    data class Step(override val tMs: Long) : WalkEvent
    data class Scan(override val tMs: Long, val scan: WifiScan) : WalkEvent
}

/**
 * A simulated person walking straight from one point to the next: a step every
 * `stepLength / speed` seconds, a completed scan every `scanIntervalMs`. Its real step
 * length may differ from what the session assumes (that is what check-ins correct).
 */
class SimulatedWalker(
    private val wifi: SimulatedWifi,
    val stepLength: Double = 0.75,
    val speed: Double = 1.2,
    val scanIntervalMs: Long = 4000,
    startMs: Long = 1_700_000_000_000,
) {
    var tMs: Long = startMs
        private set
    private var nextScanMs = startMs + scanIntervalMs
    var x = 0.0
        private set
    var y = 0.0
        private set
    var floor = 0L
        private set

    fun placeAt(px: Double, py: Double, pfloor: Long) {
        x = px; y = py; floor = pfloor
    }

    /** Walks to ([tx], [ty]) and returns the steps and scans on the way, in time order. */
    fun walkTo(tx: Double, ty: Double, tfloor: Long): List<WalkEvent> {
        val out = ArrayList<WalkEvent>()
        val d = hypot(tx - x, ty - y)
        val steps = maxOf(1, (d / stepLength).roundToInt())
        val stepMs = (stepLength / speed * 1000).toLong()
        val (x0, y0) = x to y
        for (i in 1..steps) {
            val t = tMs + stepMs
            while (nextScanMs <= t) {
                out += WalkEvent.Scan(nextScanMs, wifi.scanAt(nextScanMs, x, y, floor))
                nextScanMs += scanIntervalMs
            }
            tMs = t
            x = x0 + (tx - x0) * i / steps
            y = y0 + (ty - y0) * i / steps
            out += WalkEvent.Step(tMs)
        }
        floor = tfloor
        return out
    }

    /** Time passes without walking (a check-in tap). */
    fun pauseFor(ms: Long) {
        tMs += ms
    }
}
