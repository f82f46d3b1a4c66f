package dev.trailprint.testing

import dev.trailprint.robot.RobotDriver
import dev.trailprint.robot.SimulatedRobot
import dev.trailprint.robot.SimulatedRobotConfig
import dev.trailprint.sensors.StepEvent
import dev.trailprint.sensors.StepSource
import dev.trailprint.sensors.WifiReading
import dev.trailprint.sensors.WifiScan
import dev.trailprint.sensors.WifiScanSource
import dev.trailprint.survey.SurveySensors
import dev.trailprint.survey.WakeLockHandle
import java.util.concurrent.atomic.AtomicInteger
import kotlinx.coroutines.channels.Channel
import kotlinx.coroutines.flow.Flow
import kotlinx.coroutines.flow.onCompletion
import kotlinx.coroutines.flow.onStart
import kotlinx.coroutines.flow.receiveAsFlow

/**
 * Sensors the test drives by hand: it sends steps and completed scans, and counts requests.
 * The robot is the simulated one, its clock starting at [clock]'s time.
 */
class FakeSensors(private val clock: () -> Long = System::currentTimeMillis) : SurveySensors {
    val stepEvents = Channel<StepEvent>(Channel.UNLIMITED)
    val scanResults = Channel<WifiScan>(Channel.UNLIMITED)
    val scanRequests = AtomicInteger()
    /** Collectors of steps and scans right now (the sensors are on while this is > 0). */
    val listening = AtomicInteger()

    fun step() = stepEvents.trySend(StepEvent(System.nanoTime())).getOrThrow()

    fun scan(tMs: Long, vararg readings: Pair<String, Int>) =
        scanResults.trySend(WifiScan(tMs, readings.map { WifiReading(it.first, it.second) })).getOrThrow()

    private fun <T> Flow<T>.counted() = onStart { listening.incrementAndGet() }.onCompletion { listening.decrementAndGet() }

    override fun steps(): StepSource = object : StepSource {
        override fun steps(): Flow<StepEvent> = stepEvents.receiveAsFlow().counted()
    }

    override fun wifi(): WifiScanSource = object : WifiScanSource {
        override fun results(): Flow<WifiScan> = scanResults.receiveAsFlow().counted()
        override fun requestScan(): Boolean {
            scanRequests.incrementAndGet()
            return true
        }
    }

    override fun robot(rosbridgeUrl: String?): RobotDriver = SimulatedRobot(SimulatedRobotConfig(speed = 2.0, startTimeMs = clock()))
}

/** A wake lock that records what was done to it and fails the test on a double acquire. */
class CountingWakeLock : WakeLockHandle {
    @Volatile var held = false
        private set
    val acquires = AtomicInteger()
    val releases = AtomicInteger()
    val timeouts = mutableListOf<Long>()

    @Synchronized override fun acquire(timeoutMs: Long) {
        check(!held) { "wake lock acquired twice" }
        held = true
        acquires.incrementAndGet()
        timeouts += timeoutMs
    }

    @Synchronized override fun release() {
        check(held) { "wake lock released while not held" }
        held = false
        releases.incrementAndGet()
    }
}
