package dev.trailprint.sensors

import kotlinx.coroutines.flow.Flow
import kotlin.math.sqrt

/** One detected step; [timestampNanos] on the sensor clock (Android's event timestamp). */
data class StepEvent(val timestampNanos: Long)

/**
 * Where the steps of the surveyor come from. On Android: `TYPE_STEP_DETECTOR` where the
 * phone has one, else the accelerometer through [PeakStepDetector].
 */
interface StepSource {
    /** Steps as they happen; collecting starts the sensor, cancelling stops it. */
    fun steps(): Flow<StepEvent>
}

/** Tuning of [PeakStepDetector]; the defaults suit a phone held in the hand. */
data class PeakStepConfig(
    /** A step is a peak of vertical-ish acceleration (gravity removed) above this, m/s². */
    val threshold: Double = 1.2,
    /** The peak ends when the signal drops below this fraction of [threshold]. */
    val hysteresis: Double = 0.5,
    /** Steps closer than this are one step (a jolt rings), seconds. Running is ~0.3 s. */
    val minStepInterval: Double = 0.25,
    /** Time constant of the gravity estimate, seconds. */
    val gravityTau: Double = 1.0,
    /** Time constant of the smoothing of the signal, seconds. */
    val smoothingTau: Double = 0.04,
)

/**
 * Accelerometer peak detection, the fallback for phones without a step detector.
 *
 * Feed every accelerometer sample to [onSample]. The magnitude of the acceleration has
 * gravity removed by a slow moving average, is smoothed by a fast one, and a step is a
 * peak above [PeakStepConfig.threshold], reported when the signal falls back under the
 * hysteresis level, at the time of the peak; peaks closer than
 * [PeakStepConfig.minStepInterval] to the previous step are ignored.
 *
 * Android-free and deterministic: the sensor glue calls it, the host tests drive it with
 * synthetic walks.
 */
class PeakStepDetector(private val config: PeakStepConfig = PeakStepConfig()) {
    private var lastT = Long.MIN_VALUE
    private var gravity = Double.NaN
    private var smooth = 0.0
    private var inPeak = false
    private var peakValue = 0.0
    private var peakT = 0L
    private var lastStepT = Long.MIN_VALUE

    /** Steps reported so far. */
    var count: Int = 0
        private set

    /** One accelerometer sample (m/s², timestamp in ns); returns the step it completed. */
    fun onSample(timestampNanos: Long, x: Double, y: Double, z: Double): StepEvent? {
        val m = sqrt(x * x + y * y + z * z)
        if (gravity.isNaN() || timestampNanos <= lastT) {
            if (gravity.isNaN()) gravity = m
            lastT = timestampNanos
            return null
        }
        val dt = (timestampNanos - lastT) / 1e9
        lastT = timestampNanos
        gravity += (m - gravity) * dt / (config.gravityTau + dt)
        smooth += ((m - gravity) - smooth) * dt / (config.smoothingTau + dt)

        if (!inPeak) {
            if (smooth > config.threshold) {
                inPeak = true
                peakValue = smooth
                peakT = timestampNanos
            }
            return null
        }
        if (smooth > peakValue) {
            peakValue = smooth
            peakT = timestampNanos
        }
        if (smooth < config.threshold * config.hysteresis) {
            inPeak = false
            val minNs = (config.minStepInterval * 1e9).toLong()
            if (lastStepT == Long.MIN_VALUE || peakT - lastStepT >= minNs) {
                lastStepT = peakT
                count++
                return StepEvent(peakT)
            }
        }
        return null
    }

    /** Forgets everything (a new walk). */
    fun reset() {
        lastT = Long.MIN_VALUE
        gravity = Double.NaN
        smooth = 0.0
        inPeak = false
        lastStepT = Long.MIN_VALUE
        count = 0
    }
}
