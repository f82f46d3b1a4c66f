package dev.trailprint.survey

import java.util.concurrent.atomic.AtomicLong

/**
 * The platform's way of keeping the CPU running while the screen is off. On Android a
 * partial `PowerManager.WakeLock` (not reference counted: [AwakeMeter] does the counting);
 * on the host, nothing.
 */
interface WakeLockHandle {
    /** Keeps the CPU awake; the platform lets go by itself after [timeoutMs] (a safety net). */
    fun acquire(timeoutMs: Long)

    fun release()

    /** No wake lock at all (host tests, the host demo). */
    object None : WakeLockHandle {
        override fun acquire(timeoutMs: Long) = Unit
        override fun release() = Unit
    }
}

/** What [AwakeMeter] measured since it was made. */
data class AwakeSummary(
    /** Events handled with the CPU held awake. */
    val holds: Long,
    /** Time the wake lock was held (overlapping holds counted once), ms. */
    val heldMs: Long,
    /** Time since the meter was made, ms. */
    val elapsedMs: Long,
) {
    /** Held time over elapsed time, 0 to 1 (0 before any time passed). */
    val fraction: Double get() = if (elapsedMs <= 0) 0.0 else heldMs.toDouble() / elapsedMs

    /** One line for the survey screen: what the survey costs in CPU time. */
    fun message(): String = "CPU kept awake %.1f%% of the survey (%d events, %.1f s held)".format(100 * fraction, holds, heldMs / 1000.0)
}

/**
 * Holds the CPU awake only while one event (a step, a scan, a pose, a check-in) is being
 * handled, and measures how much of the survey that is.
 *
 * The lock is acquired when the first of possibly overlapping holds begins and released
 * when the last one ends, whatever the outcome of the handling (an exception releases it
 * too). Every hold also passes [timeoutMs] to the platform, so a handler stuck in native
 * code cannot keep the phone awake for longer than that.
 *
 * Thread-safe: holds may start and end on any thread.
 */
class AwakeMeter(
    private val lock: WakeLockHandle,
    private val clock: () -> Long = System::currentTimeMillis,
    private val timeoutMs: Long = 10_000,
) {
    private val guard = Any()
    private val startedMs = clock()
    private var depth = 0
    private var heldSinceMs = 0L
    private var heldMs = 0L
    private val holds = AtomicLong()

    /** True while some event is being handled. */
    val isHeld: Boolean get() = synchronized(guard) { depth > 0 }

    /** Runs [block] with the CPU held awake. */
    suspend fun <T> held(block: suspend () -> T): T {
        begin()
        try {
            return block()
        } finally {
            end()
        }
    }

    private fun begin() = synchronized(guard) {
        holds.incrementAndGet()
        if (depth++ == 0) {
            heldSinceMs = clock()
            lock.acquire(timeoutMs)
        }
    }

    private fun end() = synchronized(guard) {
        if (--depth == 0) {
            heldMs += maxOf(0L, clock() - heldSinceMs)
            lock.release()
        }
    }

    fun summary(): AwakeSummary = synchronized(guard) {
        val now = clock()
        val current = if (depth > 0) maxOf(0L, now - heldSinceMs) else 0L
        AwakeSummary(holds.get(), heldMs + current, maxOf(0L, now - startedMs))
    }
}
