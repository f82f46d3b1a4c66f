package dev.trailprint.survey

import dev.trailprint.ffi.EventAck
import dev.trailprint.ffi.Guidance
import dev.trailprint.ffi.Position
import dev.trailprint.ffi.ReplanOutcome
import dev.trailprint.ffi.SessionProgress
import dev.trailprint.ffi.SessionStatus
import dev.trailprint.ffi.SessionSummary
import dev.trailprint.ffi.SurveySession
import dev.trailprint.ffi.TrailprintException
import dev.trailprint.ffi.WifiReading
import dev.trailprint.robot.RobotDriver
import dev.trailprint.robot.RobotPose
import dev.trailprint.robot.Waypoint
import dev.trailprint.sensors.ScanIntervalStats
import dev.trailprint.sensors.ScanPacer
import dev.trailprint.sensors.ScanIntervalSummary
import dev.trailprint.sensors.StepSource
import dev.trailprint.sensors.WifiScan
import dev.trailprint.sensors.WifiScanSource
import kotlinx.coroutines.CoroutineDispatcher
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.Job
import kotlinx.coroutines.delay
import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asStateFlow
import kotlinx.coroutines.flow.update
import kotlinx.coroutines.launch
import kotlinx.coroutines.sync.Mutex
import kotlinx.coroutines.sync.withLock
import kotlinx.coroutines.withContext

/** What the survey screen shows, refreshed after every event. */
data class SurveyLive(
    val progress: SessionProgress? = null,
    val guidance: Guidance? = null,
    val lastAck: EventAck? = null,
    /** Position estimates after each event, oldest first (the walked part). */
    val track: List<Position> = emptyList(),
    val scans: ScanIntervalSummary? = null,
    val lastReplan: ReplanOutcome? = null,
    val summary: SessionSummary? = null,
    /** How much of the survey the CPU was held awake for (see [AwakeMeter]). */
    val awake: AwakeSummary? = null,
    val error: String? = null,
) {
    val status: SessionStatus? get() = progress?.status ?: guidance?.status
}

/**
 * Turns sensor events into session calls, in order, off the main thread, and publishes
 * the session's progress and guidance after each one.
 *
 * Events go through one lock so that they reach the session in the order they happened,
 * and their times are clamped to never go backwards (the session rejects that). A
 * rejected event (for example a scan after finish) becomes [SurveyLive.error]; the
 * session is unchanged by it.
 *
 * Every event is handled inside [awake]'s hold: the CPU is kept awake from the moment the
 * event reaches the controller until the session acknowledged it (it is on disk), and
 * released in between, so a survey in a pocket costs CPU time only per event.
 */
class SurveyController(
    val session: SurveySession,
    private val scope: CoroutineScope,
    private val io: CoroutineDispatcher = Dispatchers.IO,
    private val clock: () -> Long = System::currentTimeMillis,
    private val scanStats: ScanIntervalStats = ScanIntervalStats(),
    val awake: AwakeMeter = AwakeMeter(WakeLockHandle.None, clock),
) {
    private val _state = MutableStateFlow(SurveyLive())
    val state: StateFlow<SurveyLive> = _state.asStateFlow()
    private val order = Mutex()
    private var lastT = Long.MIN_VALUE
    private val jobs = mutableListOf<Job>()

    /** Loads the current progress and guidance (after start or resume). */
    suspend fun refresh() = withContext(io) {
        val track = session.samples().map { it.position }
        publish(null, track)
    }

    private fun publish(ack: EventAck?, track: List<Position>? = null) {
        val progress = session.progress()
        val guidance = session.guidance()
        _state.update {
            it.copy(
                progress = progress,
                guidance = guidance,
                lastAck = ack ?: it.lastAck,
                track = track ?: if (ack != null) it.track + ack.position else it.track,
                scans = scanStats.summary(),
                awake = awake.summary(),
                error = null,
            )
        }
    }

    /** Runs one session call in order with a non-decreasing time; null if it was rejected. */
    private suspend fun <T> event(t: Long?, call: (Long) -> T): T? = awake.held {
        order.withLock { eventLocked(t, call) }
    }

    private suspend fun <T> eventLocked(t: Long?, call: (Long) -> T): T? =
        withContext(io) {
            val now = maxOf(t ?: clock(), lastT)
            try {
                val r = call(now)
                lastT = now
                // Progress and guidance read here: off the caller's thread, inside the hold.
                if (r is EventAck) publish(r)
                r
            } catch (e: TrailprintException) {
                _state.update { it.copy(error = e.message) }
                null
            }
        }

    suspend fun step(t: Long? = null, steps: UInt = 1u): EventAck? =
        event(t) { session.step(it, steps) }

    suspend fun scan(scan: WifiScan): EventAck? {
        scanStats.onScanCompleted(scan.timestampMs)
        val readings = scan.readings.map { WifiReading(it.bssid, it.rssDbm.toDouble()) }
        return event(scan.timestampMs) { session.scan(it, readings) }
    }

    /** The surveyor confirms being at [vertex] (the big button checks in at the next one). */
    suspend fun checkIn(vertex: String, t: Long? = null): EventAck? =
        event(t) { session.checkIn(it, vertex) }

    /** Checks in at the vertex the guidance expects next. */
    suspend fun checkInAtNext(t: Long? = null): EventAck? {
        val g = _state.value.guidance ?: withContext(io) { session.guidance() }
        val v = g.nextVertex ?: return null
        return checkIn(v, t)
    }

    suspend fun robotPose(p: RobotPose): EventAck? =
        event(p.timestampMs) { session.robotPose(it, p.x, p.y, p.floor) }

    suspend fun pause(t: Long? = null) = event(t) { session.pause(it) }

    suspend fun resume(t: Long? = null) = event(t) { session.resume(it) }

    suspend fun abort(reason: String?, t: Long? = null) = event(t) { session.abort(it, reason) }

    /** Plans the rest of the walk again from here. */
    suspend fun replan(): ReplanOutcome? = order.withLock {
        withContext(io) {
            try {
                session.replan().also { r ->
                    publish(null)
                    _state.update { it.copy(lastReplan = r) }
                }
            } catch (e: TrailprintException) {
                _state.update { it.copy(error = e.message) }
                null
            }
        }
    }

    suspend fun finish(t: Long? = null): SessionSummary? {
        stopSensors()
        val summary = event(t) { session.finish(it) } ?: return null
        withContext(io) { publish(null) }
        _state.update { it.copy(summary = summary) }
        return summary
    }

    /**
     * Human mode: feeds every step and every completed scan to the session. A scan is
     * requested while a step is being handled (the CPU is awake for it anyway) once
     * [pacer]'s interval has passed; a timer asks too, for when the surveyor stands still
     * with the screen on (with the screen off and the CPU asleep the timer simply waits).
     */
    fun attachHumanSensors(steps: StepSource, scans: WifiScanSource, pacer: ScanPacer = ScanPacer(4000)) {
        jobs += scope.launch { scans.results().collect { scan(it) } }
        jobs += scope.launch {
            steps.steps().collect {
                awake.held {
                    step()
                    requestScanIfDue(scans, pacer)
                }
            }
        }
        jobs += scope.launch { scanTimer(scans, pacer) }
    }

    /** Robot mode: feeds every pose and every scan to the session; scans paced as for a person. */
    fun attachRobot(driver: RobotDriver, scans: WifiScanSource?, pacer: ScanPacer = ScanPacer(1000)) {
        if (scans != null) {
            jobs += scope.launch { scans.results().collect { scan(it) } }
            jobs += scope.launch { scanTimer(scans, pacer) }
        }
        jobs += scope.launch {
            driver.poses.collect { p ->
                awake.held {
                    robotPose(p)
                    if (scans != null) requestScanIfDue(scans, pacer)
                }
            }
        }
    }

    private suspend fun scanTimer(scans: WifiScanSource, pacer: ScanPacer) {
        while (true) {
            delay(pacer.intervalMs)
            awake.held { requestScanIfDue(scans, pacer) }
        }
    }

    private fun requestScanIfDue(scans: WifiScanSource, pacer: ScanPacer) {
        if (pacer.due(clock()) && !scans.requestScan()) scanStats.onScanRequestRejected()
    }

    /** The waypoints still ahead, with positions, for a robot to drive. */
    suspend fun waypointsAhead(positions: Map<String, Position>): List<Waypoint> = withContext(io) {
        session.routeAhead().mapNotNull { w ->
            positions[w.vertex]?.let { Waypoint(w.vertex, it.x, it.y, it.floor) }
        }
    }

    fun stopSensors() {
        jobs.forEach { it.cancel() }
        jobs.clear()
    }

    fun dismissError() = _state.update { it.copy(error = null) }
}
