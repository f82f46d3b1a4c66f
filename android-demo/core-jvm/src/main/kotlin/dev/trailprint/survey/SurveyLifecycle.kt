package dev.trailprint.survey

import dev.trailprint.AppException
import dev.trailprint.Trailprint
import dev.trailprint.ffi.BuildingMap
import dev.trailprint.ffi.PlanSummary
import dev.trailprint.ffi.Position
import dev.trailprint.ffi.SessionStatus
import dev.trailprint.ffi.SessionSummary
import dev.trailprint.ffi.SurveySession
import dev.trailprint.ffi.SurveyorProfile
import dev.trailprint.ffi.TrailprintException
import dev.trailprint.ffi.defaultHumanProfile
import dev.trailprint.ffi.defaultRobotProfile
import dev.trailprint.robot.CleartextPolicy
import dev.trailprint.robot.RobotDriver
import dev.trailprint.robot.RobotException
import dev.trailprint.sensors.ScanPacer
import dev.trailprint.sensors.StepSource
import dev.trailprint.sensors.WifiScanSource
import kotlinx.coroutines.CoroutineDispatcher
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.Job
import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asStateFlow
import kotlinx.coroutines.flow.update
import kotlinx.coroutines.launch
import kotlinx.coroutines.sync.Mutex
import kotlinx.coroutines.sync.withLock
import kotlinx.coroutines.withContext

/** Where the survey's sensors come from: Android's in the app, simulated ones on the host. */
interface SurveySensors {
    fun steps(): StepSource
    fun wifi(): WifiScanSource
    /** The robot to drive in robot mode: rosbridge at [rosbridgeUrl], or the simulated one (null). */
    fun robot(rosbridgeUrl: String?): RobotDriver
}

/** Where a survey is in its life. */
enum class SurveyPhase { IDLE, RUNNING, PAUSED, FINISHED, ABORTED }

/** Everything the service's notification and the survey screen show. */
data class LifecycleState(
    val phase: SurveyPhase = SurveyPhase.IDLE,
    val active: ActiveSurvey? = null,
    val map: BuildingMap? = null,
    val plan: PlanSummary? = null,
    val live: SurveyLive = SurveyLive(),
    /** Vertex ids still ahead on the walk. */
    val ahead: List<String> = emptyList(),
    /** The end of the last survey (finished or aborted). */
    val summary: SessionSummary? = null,
    /** Something the surveyor should read: a survey carried on after a restart, a robot error. */
    val message: String? = null,
    /**
     * The active-survey record exists but cannot be read (the message names the file and
     * the field): the screen offers [SurveyLifecycle.forgetActive] ("Forget"), since no
     * survey can start or carry on until it is gone.
     */
    val unreadableRecord: String? = null,
) {
}

/**
 * The life of one survey, Android-free so that the foreground service is a thin shell
 * around it: start, pause, resume, stop (finish) or abort, and — after the process was
 * killed — [restore], which finds the active survey in [activeFile], resumes its session
 * from the database where its event log ends and reattaches the sensors.
 *
 * Nothing acknowledged is ever lost: every event is on disk before the session
 * acknowledges it (the core's rule), and [activeFile] is written atomically right after
 * the session is created, so a process killed at any moment restarts into the same
 * session. At most one survey is active; starting another while one runs is refused.
 *
 * Operations are serialised; the sensors feed the [controller] on [scope]. Errors of the
 * native layer (`TrailprintException`) and of this one ([AppException]) are thrown to the
 * caller, who shows the message; the state is left as it was.
 */
class SurveyLifecycle(
    private val api: Trailprint,
    private val activeFile: ActiveSurveyFile,
    private val sensors: SurveySensors,
    private val scope: CoroutineScope,
    private val wakeLock: WakeLockHandle = WakeLockHandle.None,
    private val io: CoroutineDispatcher = Dispatchers.IO,
    private val clock: () -> Long = System::currentTimeMillis,
    /** How often a person's phone asks for a Wi-Fi scan, ms. */
    private val humanScanMs: Long = 4000,
    /** How often the phone on a robot asks for a Wi-Fi scan, ms. */
    private val robotScanMs: Long = 1000,
) {
    private val _state = MutableStateFlow(LifecycleState())
    val state: StateFlow<LifecycleState> = _state.asStateFlow()
    private val ops = Mutex()
    private var session: SurveySession? = null
    private var driver: RobotDriver? = null
    private val jobs = mutableListOf<Job>()

    /** The running survey's controller (null when none runs). */
    var controller: SurveyController? = null
        private set

    /** The CPU time the running survey held awake (null when none runs). */
    val awake: AwakeMeter? get() = controller?.awake

    /**
     * Starts a survey on [planId]. The surveyor model is the one the plan was made for
     * (else the default of [mode]); a plan made for a person cannot be driven by a robot or
     * the other way round. Refused while another survey is active.
     */
    suspend fun start(planId: Long, mode: SurveyMode, rosbridgeUrl: String? = null): ActiveSurvey = ops.withLock {
        val running = _state.value.active ?: try {
            activeFile.read()
        } catch (e: AppException) {
            _state.update { it.copy(unreadableRecord = e.message) }
            throw AppException("${e.message} — the record of the last survey cannot be read: forget it to start a new survey", e)
        }
        if (running != null) {
            throw AppException("a survey is already active (session ${running.sessionId}): finish or abort it before starting another")
        }
        if (mode == SurveyMode.ROBOT && rosbridgeUrl != null) CleartextPolicy.check(rosbridgeUrl)?.let { throw AppException(it) }
        val plan = api.plan(planId)
        val map = api.map(plan.buildingId)
        val planned = plan.surveyor
        if (planned != null && (planned is SurveyorProfile.Robot) != (mode == SurveyMode.ROBOT)) {
            val kind = if (planned is SurveyorProfile.Robot) "a robot" else "a person"
            throw AppException("plan $planId was made for $kind: plan again with the ${mode.name.lowercase()} profile to survey it in ${mode.name.lowercase()} mode")
        }
        val profile: SurveyorProfile = planned ?: if (mode == SurveyMode.HUMAN) defaultHumanProfile() else defaultRobotProfile()
        val s = api.startSession(planId, profile)
        val active = ActiveSurvey(s.id(), planId, mode, rosbridgeUrl, clock())
        try {
            activeFile.write(active)
        } catch (e: AppException) {
            // Without the record a restart could not find the session: do not run it.
            withContext(io) {
                s.abort(clock(), "the app could not record the active survey: ${e.message}")
                s.close()
            }
            throw e
        }
        attach(s, active, map, plan, message = null)
        active
    }

    /**
     * After a restart: carries on with the survey [activeFile] names, if any. A paused
     * survey stays paused (its sensors off); a running one gets its sensors back. A record
     * whose session has ended or is gone is cleared, and the state says why. A record that
     * cannot be read is not an exception here (a service restarted by the system would
     * fail the same way at every restart): it is [LifecycleState.unreadableRecord], for the
     * screen to offer "Forget", and nothing runs.
     */
    suspend fun restore(): ActiveSurvey? = ops.withLock {
        if (_state.value.active != null) return@withLock _state.value.active
        val active = try {
            activeFile.read()
        } catch (e: AppException) {
            _state.value = LifecycleState(unreadableRecord = e.message)
            return@withLock null
        } ?: return@withLock null
        val s = try {
            api.resumeSession(active.sessionId)
        } catch (e: TrailprintException.NotFound) {
            activeFile.clear()
            _state.value = LifecycleState(message = "The survey that was running (session ${active.sessionId}) is no longer in the database.")
            return@withLock null
        }
        val status = withContext(io) { s.status() }
        if (status == SessionStatus.FINISHED || status == SessionStatus.ABORTED) {
            val summary = withContext(io) { s.use { it.summary() } }
            activeFile.clear()
            _state.value = LifecycleState(
                phase = if (status == SessionStatus.FINISHED) SurveyPhase.FINISHED else SurveyPhase.ABORTED,
                summary = summary,
                message = "Session ${active.sessionId} had already ended.",
            )
            return@withLock null
        }
        val plan = api.plan(active.planId)
        val map = api.map(plan.buildingId)
        attach(s, active, map, plan, message = "Carried on with session ${active.sessionId} after the app was restarted.")
        active
    }

    /** Pauses the walk: the session records it and the sensors stop until [resume]. */
    suspend fun pause() = ops.withLock {
        val c = controller ?: throw AppException("no survey is running")
        c.stopSensors()
        stopDriver()
        // A rejected pause (already paused) is in the controller's error; if the session
        // still runs, so do its sensors.
        if (c.pause() == null && c.state.value.status == SessionStatus.ACTIVE) reattach(c)
    }

    /** Resumes a paused walk and restarts the sensors. */
    suspend fun resume() = ops.withLock {
        val c = controller ?: throw AppException("no survey is running")
        if (c.resume() != null) reattach(c)
    }

    private fun reattach(c: SurveyController) {
        val s = _state.value
        if (s.active != null && s.map != null) attachSensors(c, s.active, s.map)
    }

    /**
     * Forgets the active-survey record without touching its session (for a record that
     * cannot be read: the error names the file). What the session collected stays in the
     * database. Refused while a survey is attached.
     */
    suspend fun forgetActive() = ops.withLock {
        if (controller != null) throw AppException("a survey is running: stop or abort it instead")
        activeFile.clear()
        _state.update { it.copy(unreadableRecord = null) }
    }

    /** Finishes the survey: the session's summary, the active record cleared. */
    suspend fun stop(): SessionSummary? = ops.withLock {
        val c = controller ?: return@withLock null
        stopDriver()
        val summary = c.finish() ?: return@withLock null
        end(SurveyPhase.FINISHED, summary)
        summary
    }

    /** Abandons the survey (what was collected stays in the database). */
    suspend fun abort(reason: String?): SessionSummary? = ops.withLock {
        val c = controller ?: return@withLock null
        c.stopSensors()
        stopDriver()
        c.abort(reason) ?: return@withLock null
        val summary = withContext(io) { c.session.summary() }
        end(SurveyPhase.ABORTED, summary)
        summary
    }

    /**
     * Lets go of the survey without ending it (the service is being destroyed): sensors
     * off, session closed, the active record kept so that [restore] carries on.
     */
    suspend fun detach() = ops.withLock {
        stopEverything()
        _state.update { LifecycleState(message = it.message) }
    }

    fun dismissMessage() = _state.update { it.copy(message = null) }

    /** Shows [message] (an error the service met outside an operation, such as a refused start). */
    fun reportError(message: String) = _state.update { it.copy(message = message) }

    private suspend fun end(phase: SurveyPhase, summary: SessionSummary) {
        val (plan, map) = _state.value.let { it.plan to it.map }
        stopEverything()
        activeFile.clear()
        _state.value = LifecycleState(phase = phase, summary = summary, plan = plan, map = map)
    }

    private suspend fun stopEverything() {
        jobs.forEach { it.cancel() }
        jobs.clear()
        controller?.stopSensors()
        stopDriver()
        val s = session
        session = null
        controller = null
        if (s != null) withContext(io) { s.close() }
    }

    private fun stopDriver() {
        driver?.close()
        driver = null
    }

    private suspend fun attach(s: SurveySession, active: ActiveSurvey, map: BuildingMap, plan: PlanSummary, message: String?) {
        val c = SurveyController(s, scope, io, clock, awake = AwakeMeter(wakeLock, clock))
        session = s
        controller = c
        c.refresh()
        _state.value = LifecycleState(phase = phaseOf(c.state.value.status), active = active, map = map, plan = plan, live = c.state.value, message = message)
        jobs += scope.launch {
            c.state.collect { live ->
                val ahead = withContext(io) {
                    try {
                        s.routeAhead().map { it.vertex }
                    } catch (e: TrailprintException) {
                        emptyList()
                    }
                }
                _state.update { it.copy(phase = phaseOf(live.status), live = live, ahead = ahead) }
            }
        }
        if (c.state.value.status == SessionStatus.ACTIVE) attachSensors(c, active, map)
    }

    private fun phaseOf(status: SessionStatus?): SurveyPhase = when (status) {
        SessionStatus.PAUSED -> SurveyPhase.PAUSED
        SessionStatus.FINISHED -> SurveyPhase.FINISHED
        SessionStatus.ABORTED -> SurveyPhase.ABORTED
        else -> SurveyPhase.RUNNING
    }

    private fun attachSensors(c: SurveyController, active: ActiveSurvey, map: BuildingMap) {
        when (active.mode) {
            SurveyMode.HUMAN -> c.attachHumanSensors(sensors.steps(), sensors.wifi(), ScanPacer(humanScanMs))
            SurveyMode.ROBOT -> {
                val d = sensors.robot(active.rosbridgeUrl)
                driver = d
                c.attachRobot(d, sensors.wifi(), ScanPacer(robotScanMs))
                val positions = map.vertices.associate { it.id to Position(it.x, it.y, it.floor) }
                jobs += scope.launch {
                    try {
                        d.follow(c.waypointsAhead(positions))
                    } catch (e: RobotException) {
                        _state.update { it.copy(message = "Robot: ${e.message}") }
                    }
                }
            }
        }
    }
}
