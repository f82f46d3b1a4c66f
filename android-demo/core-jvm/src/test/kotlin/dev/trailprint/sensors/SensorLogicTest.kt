package dev.trailprint.sensors

import java.util.Random
import kotlin.math.PI
import kotlin.math.sin
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertFalse
import kotlin.test.assertNotNull
import kotlin.test.assertNull
import kotlin.test.assertTrue

class PeakStepDetectorTest {
    /** Feeds [seconds] of a 50 Hz accelerometer; [vertical] gives the extra vertical acceleration. */
    private fun run(d: PeakStepDetector, seconds: Double, noise: Double, seed: Long = 3, vertical: (Double) -> Double): List<StepEvent> {
        val r = Random(seed)
        val out = mutableListOf<StepEvent>()
        val n = (seconds * 50).toInt()
        for (i in 0..n) {
            val t = i / 50.0
            val z = 9.81 + vertical(t) + r.nextGaussian() * noise
            d.onSample((t * 1e9).toLong(), r.nextGaussian() * noise, r.nextGaussian() * noise, z)?.let { out += it }
        }
        return out
    }

    @Test
    fun countsStepsOfASteadyWalk() {
        val d = PeakStepDetector()
        // 1.9 steps per second for 20 s, 3 m/s² bounce, plus sensor noise.
        val steps = run(d, 20.0, noise = 0.3) { t -> 3.0 * sin(2 * PI * 1.9 * t) }
        assertTrue(steps.size in 36..39, "expected about 38 steps, got ${steps.size}")
        assertEquals(steps.size, d.count)
        val gaps = steps.zipWithNext { a, b -> (b.timestampNanos - a.timestampNanos) / 1e9 }
        assertTrue(gaps.all { it > 0.4 && it < 0.65 }, "step intervals $gaps")
    }

    @Test
    fun standingStillIsNoStep() {
        val steps = run(PeakStepDetector(), 10.0, noise = 0.25) { 0.0 }
        assertEquals(0, steps.size)
    }

    @Test
    fun aRingingJoltIsOneStep() {
        // A 0.15 s ringing after a jolt: two peaks closer than the minimum step interval.
        val steps = run(PeakStepDetector(), 3.0, noise = 0.0) { t ->
            if (t in 1.0..1.16) 6.0 * sin(2 * PI * (t - 1.0) / 0.08) else 0.0
        }
        assertEquals(1, steps.size)
    }
}

class ScanIntervalStatsTest {
    @Test
    fun measuresTheIntervalOfUnthrottledScans() {
        val s = ScanIntervalStats(window = 10, requestedInterval = 4.0)
        assertNull(s.summary())
        var t = 1_000_000L
        for (i in 0 until 12) {
            s.onScanCompleted(t)
            t += if (i % 2 == 0) 3800 else 4200
        }
        val sum = assertNotNull(s.summary())
        assertEquals(10, sum.scans)
        assertEquals(4.0, sum.effectiveInterval, 0.05)
        assertEquals(3.8, sum.min, 1e-9)
        assertEquals(4.2, sum.max, 1e-9)
        assertFalse(sum.throttled)
        assertTrue("4.0 s" in sum.message(), sum.message())
    }

    @Test
    fun seesAndroidsFourScansPerTwoMinutes() {
        val s = ScanIntervalStats(window = 16, requestedInterval = 4.0)
        var t = 0L
        repeat(3) {
            repeat(4) { s.onScanCompleted(t); t += 4000 }
            t += 120_000 - 16_000
        }
        val sum = assertNotNull(s.summary())
        assertTrue(sum.throttled)
        assertTrue(sum.effectiveInterval > 20, "${sum.effectiveInterval}")
        assertTrue("throttl" in sum.message(), sum.message())
    }

    @Test
    fun aRefusedRequestMeansThrottled() {
        val s = ScanIntervalStats()
        s.onScanCompleted(0)
        s.onScanCompleted(4000)
        s.onScanRequestRejected()
        assertTrue(s.summary()!!.throttled)
    }

    @Test
    fun quantileIsNearestRank() {
        val v = listOf(1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0)
        assertEquals(5.0, ScanIntervalStats.quantile(v, 0.5))
        assertEquals(9.0, ScanIntervalStats.quantile(v, 0.9))
        assertEquals(1.0, ScanIntervalStats.quantile(v, 0.0))
    }
}
