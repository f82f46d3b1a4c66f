package dev.trailprint.robot

import java.util.Random
import kotlin.math.atan2
import kotlin.math.hypot
import kotlinx.coroutines.currentCoroutineContext
import kotlinx.coroutines.delay
import kotlinx.coroutines.ensureActive
import kotlinx.coroutines.flow.MutableSharedFlow
import kotlinx.coroutines.flow.SharedFlow
import kotlinx.coroutines.flow.asSharedFlow

/** Settings of [SimulatedRobot]. */
data class SimulatedRobotConfig(
    /** Constant driving speed, m/s. */
    val speed: Double = 0.5,
    /** Time between reported poses, ms (of simulated time). */
    val poseIntervalMs: Long = 200,
    /** Standard deviation of the position noise of reported poses (SLAM error), m. */
    val poseNoise: Double = 0.0,
    /** Seed of the noise. */
    val seed: Long = 1,
    /** Simulated time runs this many times faster than real time (0: no waiting at all). */
    val timeScale: Double = 1.0,
    /** Simulated clock at the start, ms. */
    val startTimeMs: Long = 0,
)

/**
 * A kinematic robot: drives straight from waypoint to waypoint at constant speed, turning
 * on the spot, and reports a pose every `poseIntervalMs` of simulated time (plus the exact
 * pose at each waypoint). Deterministic for a seed. [trajectory] is the pure computation;
 * [follow] plays it out on [poses] in (scaled) real time.
 */
class SimulatedRobot(private val config: SimulatedRobotConfig = SimulatedRobotConfig()) : RobotDriver {
    init {
        require(config.speed > 0 && config.speed.isFinite()) { "speed must be positive, got ${config.speed}" }
        require(config.poseIntervalMs > 0) { "pose interval must be positive, got ${config.poseIntervalMs}" }
    }

    private val flow = MutableSharedFlow<RobotPose>(extraBufferCapacity = 4096)
    override val poses: SharedFlow<RobotPose> = flow.asSharedFlow()
    private val random = Random(config.seed)
    @Volatile private var stopped = false

    /** Simulated clock, ms: advances as the robot drives. */
    var clockMs: Long = config.startTimeMs
        private set

    /** The last pose reported. */
    var lastPose: RobotPose? = null
        private set

    /**
     * The poses the robot reports driving [waypoints] from the first one, starting at
     * simulated time [startMs]: one every pose interval, plus one at every waypoint.
     */
    fun trajectory(waypoints: List<Waypoint>, startMs: Long = clockMs): List<RobotPose> {
        if (waypoints.isEmpty()) return emptyList()
        val out = ArrayList<RobotPose>()
        var t = startMs.toDouble()
        val w0 = waypoints[0]
        var heading = if (waypoints.size > 1) atan2(waypoints[1].y - w0.y, waypoints[1].x - w0.x) else 0.0
        out += pose(t, w0.x, w0.y, w0.floor, heading)
        var nextReport = t + config.poseIntervalMs
        for (i in 1 until waypoints.size) {
            val a = waypoints[i - 1]
            val b = waypoints[i]
            val d = hypot(b.x - a.x, b.y - a.y)
            if (d > 0) heading = atan2(b.y - a.y, b.x - a.x)
            val legMs = d / config.speed * 1000.0
            val legStart = t
            // The pose at the previous waypoint already covers this instant.
            while (nextReport <= legStart) nextReport += config.poseIntervalMs
            while (nextReport < legStart + legMs) {
                val f = (nextReport - legStart) / legMs
                out += pose(nextReport, a.x + (b.x - a.x) * f, a.y + (b.y - a.y) * f, if (f < 0.5) a.floor else b.floor, heading)
                nextReport += config.poseIntervalMs
            }
            t = legStart + legMs
            out += pose(t, b.x, b.y, b.floor, heading)
        }
        return out
    }

    private fun pose(tMs: Double, x: Double, y: Double, floor: Long, heading: Double): RobotPose {
        val n = config.poseNoise
        val nx = if (n > 0) random.nextGaussian() * n else 0.0
        val ny = if (n > 0) random.nextGaussian() * n else 0.0
        return RobotPose(Math.round(tMs), x + nx, y + ny, floor, heading)
    }

    override suspend fun follow(waypoints: List<Waypoint>) {
        stopped = false
        val traj = trajectory(waypoints)
        var prevT = traj.firstOrNull()?.timestampMs ?: return
        for (p in traj) {
            currentCoroutineContext().ensureActive()
            if (stopped) throw RobotException("stopped")
            if (config.timeScale > 0) {
                val waitMs = ((p.timestampMs - prevT) / config.timeScale).toLong()
                if (waitMs > 0) delay(waitMs)
            }
            prevT = p.timestampMs
            clockMs = p.timestampMs
            lastPose = p
            flow.emit(p)
        }
    }

    override fun stop() {
        stopped = true
    }
}
