package dev.trailprint.sensors

import kotlinx.coroutines.flow.Flow
import kotlin.math.ceil

/** One access point heard in a scan. */
data class WifiReading(val bssid: String, val rssDbm: Int, val ssid: String? = null, val frequencyMhz: Int? = null)

/** A completed Wi-Fi scan: when it completed (wall clock, ms) and what it heard. */
data class WifiScan(val timestampMs: Long, val readings: List<WifiReading>)

/**
 * Completed Wi-Fi scans. On Android: `WifiManager.startScan()` plus the
 * `SCAN_RESULTS_AVAILABLE_ACTION` broadcast. Android 9+ throttles foreground apps to 4
 * scans in 2 minutes unless "Wi-Fi scan throttling" is turned off in the developer
 * options; measure the real interval with [ScanIntervalStats] and tell the surveyor.
 *
 * Requesting and receiving are separate so that the survey asks for a scan while it is
 * awake anyway (handling a step or a robot pose, see [ScanPacer]) instead of running a
 * timer that would need the CPU kept awake for the whole survey.
 */
interface WifiScanSource {
    /** Scans as they complete; collecting registers for the results, cancelling unregisters. */
    fun results(): Flow<WifiScan>

    /** Asks for a scan now; false when the system refused (throttled, Wi-Fi off). */
    fun requestScan(): Boolean
}

/**
 * When to ask for the next Wi-Fi scan: at most one request per [intervalMs], decided each
 * time the survey handles a sensor event (a step, a robot pose) or its fallback timer
 * fires. Pure and clock-free: the caller passes the time.
 */
class ScanPacer(val intervalMs: Long) {
    init {
        require(intervalMs > 0) { "scan interval must be positive, got $intervalMs ms" }
    }

    private var lastRequestMs = Long.MIN_VALUE

    /** True (and the request counted as made at [nowMs]) when a scan is due. */
    fun due(nowMs: Long): Boolean {
        if (lastRequestMs != Long.MIN_VALUE && nowMs - lastRequestMs < intervalMs) return false
        lastRequestMs = nowMs
        return true
    }
}

/** What [ScanIntervalStats] measured. Times in seconds. */
data class ScanIntervalSummary(
    val scans: Int,
    val rejectedRequests: Int,
    /** Elapsed time over completed scans minus one: the interval the survey really gets. */
    val effectiveInterval: Double,
    val median: Double,
    val p90: Double,
    val min: Double,
    val max: Double,
    /** True when the scans look throttled (see [ScanIntervalStats.isThrottled]). */
    val throttled: Boolean,
) {
    /** A one-line message for the surveyor. */
    fun message(): String = if (throttled) {
        "Wi-Fi scans are throttled: one every %.0f s on average. Turn off \"Wi-Fi scan throttling\" in the developer options for denser fingerprints.".format(effectiveInterval)
    } else {
        "Wi-Fi scans every %.1f s (median %.1f s).".format(effectiveInterval, median)
    }
}

/**
 * The real scan interval, measured over a sliding window of completed scans, and a verdict
 * on throttling. Feed it the completion times of scans ([onScanCompleted]) and the scan
 * requests that the system refused ([onScanRequestRejected]: `startScan()` returned false).
 *
 * The effective interval is what the surveyor model's `scan_interval` should be: with the
 * walking speed it sets the sample spacing that the planner assumes.
 */
class ScanIntervalStats(
    private val window: Int = 16,
    /** The interval the app asks for, s. */
    private val requestedInterval: Double = 4.0,
) {
    init {
        require(window >= 2) { "window must hold at least 2 scans, got $window" }
    }

    private val times = ArrayDeque<Long>()
    private var rejected = 0

    fun onScanCompleted(timestampMs: Long) {
        if (times.isNotEmpty() && timestampMs < times.last()) return // clock went back: ignore
        times.addLast(timestampMs)
        while (times.size > window) times.removeFirst()
    }

    fun onScanRequestRejected() {
        rejected++
    }

    /** Null until two scans completed. */
    fun summary(): ScanIntervalSummary? {
        if (times.size < 2) return null
        val gaps = times.zipWithNext { a, b -> (b - a) / 1000.0 }.sorted()
        val effective = (times.last() - times.first()) / 1000.0 / (times.size - 1)
        return ScanIntervalSummary(
            scans = times.size,
            rejectedRequests = rejected,
            effectiveInterval = effective,
            median = quantile(gaps, 0.5),
            p90 = quantile(gaps, 0.9),
            min = gaps.first(),
            max = gaps.last(),
            throttled = isThrottled(effective, gaps),
        )
    }

    /**
     * Throttled when requests were refused, or when the effective interval is more than
     * twice the requested one and some gap reaches 25 s (Android's 4-per-2-minutes pattern:
     * a burst, then a long wait).
     */
    private fun isThrottled(effective: Double, gaps: List<Double>): Boolean =
        rejected > 0 || (effective > 2 * requestedInterval && gaps.last() >= 25.0)

    companion object {
        /** Nearest-rank quantile of sorted values. */
        fun quantile(sorted: List<Double>, q: Double): Double {
            require(sorted.isNotEmpty()) { "no values" }
            val rank = ceil(q * sorted.size).toInt().coerceIn(1, sorted.size)
            return sorted[rank - 1]
        }
    }
}
