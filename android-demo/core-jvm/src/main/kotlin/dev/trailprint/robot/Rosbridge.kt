package dev.trailprint.robot

import dev.trailprint.json.Json
import dev.trailprint.json.double
import dev.trailprint.json.path
import java.util.concurrent.ConcurrentHashMap
import java.util.concurrent.atomic.AtomicLong
import kotlin.math.atan2
import kotlin.math.cos
import kotlin.math.hypot
import kotlin.math.sin
import kotlinx.coroutines.CompletableDeferred
import kotlinx.coroutines.flow.MutableSharedFlow
import kotlinx.coroutines.flow.SharedFlow
import kotlinx.coroutines.flow.asSharedFlow

/**
 * A text WebSocket, the only transport the rosbridge client needs. The Android app adapts
 * OkHttp's WebSocket to it; the tests use a fake.
 */
interface WebSocketConnection {
    /** Queues a text frame; false when the socket is closed. */
    fun send(text: String): Boolean
    fun close()
}

/** Callbacks of a [WebSocketConnection], called on the transport's thread. */
interface WebSocketListener {
    fun onMessage(text: String)
    fun onClosed(reason: String)
}

/** Opens WebSocket connections (OkHttp on Android). */
fun interface WebSocketFactory {
    fun connect(url: String, listener: WebSocketListener): WebSocketConnection
}

/** How goals are sent and poses read. */
enum class GoalMode {
    /** The Nav2 `NavigateToPose` action (`send_action_goal`, rosbridge 2.x on ROS 2). */
    NAV2_ACTION,
    /** A `geometry_msgs/msg/PoseStamped` published on the goal topic (RViz's "2D Goal Pose"). */
    GOAL_POSE_TOPIC,
}

/**
 * Settings of the rosbridge client. The building frame maps to the robot's `map` frame by
 * a rotation [mapYaw] then a shift ([mapX], [mapY]): `map = R(yaw) * building + shift`.
 */
data class RosbridgeConfig(
    val url: String = "ws://robot.local:9090",
    val goalMode: GoalMode = GoalMode.NAV2_ACTION,
    val actionName: String = "/navigate_to_pose",
    val actionType: String = "nav2_msgs/action/NavigateToPose",
    val goalTopic: String = "/goal_pose",
    /** `/amcl_pose` (PoseWithCovarianceStamped) or `/odom` (nav_msgs/msg/Odometry). */
    val poseTopic: String = "/amcl_pose",
    val poseType: String = "geometry_msgs/msg/PoseWithCovarianceStamped",
    val frameId: String = "map",
    /** rosbridge sends at most one pose message per this many ms. */
    val poseThrottleMs: Int = 200,
    /** In topic mode, a goal counts as reached within this distance, m. */
    val goalTolerance: Double = 0.3,
    val mapX: Double = 0.0,
    val mapY: Double = 0.0,
    val mapYaw: Double = 0.0,
    /** The floor reported with every pose (a ROS map is one floor). */
    val floor: Long = 0,
)

/** Messages from rosbridge that the client understands. */
sealed class RosbridgeIncoming {
    /** A pose on the subscribed topic (already in building coordinates). */
    data class Pose(val x: Double, val y: Double, val heading: Double) : RosbridgeIncoming()
    data class ActionFeedback(val id: String, val distanceRemaining: Double?) : RosbridgeIncoming()
    /** `status` is the action's GoalStatus (4 succeeded, 5 cancelled, 6 aborted). */
    data class ActionResult(val id: String, val status: Int?, val ok: Boolean) : RosbridgeIncoming()
    data class Status(val level: String, val msg: String) : RosbridgeIncoming()
    data class Other(val op: String?) : RosbridgeIncoming()
}

/**
 * The rosbridge v2 JSON protocol, encoding and decoding only (no I/O): every message the
 * driver sends or reads goes through here, and the host tests check them.
 */
class RosbridgeProtocol(private val config: RosbridgeConfig) {
    /** Building → map frame. */
    fun toMap(x: Double, y: Double): Pair<Double, Double> {
        val c = cos(config.mapYaw)
        val s = sin(config.mapYaw)
        return Pair(c * x - s * y + config.mapX, s * x + c * y + config.mapY)
    }

    /** Map frame → building. */
    fun toBuilding(x: Double, y: Double): Pair<Double, Double> {
        val c = cos(config.mapYaw)
        val s = sin(config.mapYaw)
        val dx = x - config.mapX
        val dy = y - config.mapY
        return Pair(c * dx + s * dy, -s * dx + c * dy)
    }

    /** A `geometry_msgs/msg/PoseStamped` for a goal at building position (x, y), heading [yaw]. */
    fun poseStamped(x: Double, y: Double, yaw: Double): Map<String, Any?> {
        val (mx, my) = toMap(x, y)
        val myaw = yaw + config.mapYaw
        return mapOf(
            "header" to mapOf("frame_id" to config.frameId, "stamp" to mapOf("sec" to 0, "nanosec" to 0)),
            "pose" to mapOf(
                "position" to mapOf("x" to mx, "y" to my, "z" to 0.0),
                "orientation" to mapOf("x" to 0.0, "y" to 0.0, "z" to sin(myaw / 2), "w" to cos(myaw / 2)),
            ),
        )
    }

    fun subscribePose(): String = Json.encode(
        mapOf("op" to "subscribe", "id" to "trailprint-pose", "topic" to config.poseTopic, "type" to config.poseType, "throttle_rate" to config.poseThrottleMs),
    )

    fun unsubscribePose(): String = Json.encode(mapOf("op" to "unsubscribe", "id" to "trailprint-pose", "topic" to config.poseTopic))

    fun advertiseGoal(): String = Json.encode(
        mapOf("op" to "advertise", "topic" to config.goalTopic, "type" to "geometry_msgs/msg/PoseStamped"),
    )

    fun publishGoal(x: Double, y: Double, yaw: Double): String = Json.encode(
        mapOf("op" to "publish", "topic" to config.goalTopic, "msg" to poseStamped(x, y, yaw)),
    )

    fun sendActionGoal(id: String, x: Double, y: Double, yaw: Double): String = Json.encode(
        mapOf(
            "op" to "send_action_goal", "id" to id, "action" to config.actionName, "action_type" to config.actionType,
            "args" to mapOf("pose" to poseStamped(x, y, yaw)), "feedback" to true,
        ),
    )

    fun cancelActionGoal(id: String): String = Json.encode(
        mapOf("op" to "cancel_action_goal", "id" to id, "action" to config.actionName),
    )

    /** Reads one message; unknown or malformed messages become [RosbridgeIncoming.Other]. */
    fun decode(text: String): RosbridgeIncoming {
        val m = try {
            Json.parse(text)
        } catch (e: Exception) {
            return RosbridgeIncoming.Other(null)
        }
        val op = m.path("op") as? String
        return when (op) {
            "publish" -> {
                if (m.path("topic") != config.poseTopic) return RosbridgeIncoming.Other(op)
                // PoseWithCovarianceStamped and Odometry both keep the pose at msg.pose.pose;
                // a plain PoseStamped keeps it at msg.pose.
                val msg = m.path("msg")
                val pose = msg.path("pose", "pose").takeIf { it.path("position") != null } ?: msg.path("pose")
                val px = pose.double("position", "x") ?: return RosbridgeIncoming.Other(op)
                val py = pose.double("position", "y") ?: return RosbridgeIncoming.Other(op)
                val qz = pose.double("orientation", "z") ?: 0.0
                val qw = pose.double("orientation", "w") ?: 1.0
                val qx = pose.double("orientation", "x") ?: 0.0
                val qy = pose.double("orientation", "y") ?: 0.0
                val yawMap = atan2(2 * (qw * qz + qx * qy), 1 - 2 * (qy * qy + qz * qz))
                val (bx, by) = toBuilding(px, py)
                RosbridgeIncoming.Pose(bx, by, yawMap - config.mapYaw)
            }
            "action_feedback" -> RosbridgeIncoming.ActionFeedback(
                m.path("id") as? String ?: "",
                m.double("values", "distance_remaining") ?: m.double("values", "feedback", "distance_remaining"),
            )
            "action_result" -> RosbridgeIncoming.ActionResult(
                m.path("id") as? String ?: "",
                (m.path("status") as? Double)?.toInt(),
                m.path("result") as? Boolean ?: false,
            )
            "status" -> RosbridgeIncoming.Status(m.path("level") as? String ?: "", m.path("msg") as? String ?: "")
            else -> RosbridgeIncoming.Other(op)
        }
    }

    companion object {
        const val STATUS_SUCCEEDED = 4
        const val STATUS_CANCELED = 5
        const val STATUS_ABORTED = 6
    }
}

/**
 * A ROS 2 robot through rosbridge (`ros2 launch rosbridge_server
 * rosbridge_websocket_launch.xml`): subscribes to the pose topic, and drives each waypoint
 * as a Nav2 `NavigateToPose` goal (or a `/goal_pose` publish, considered reached within
 * the tolerance). Poses arrive in building coordinates on [poses].
 */
class RosbridgeRobotDriver(
    private val factory: WebSocketFactory,
    private val config: RosbridgeConfig = RosbridgeConfig(),
    private val clock: () -> Long = System::currentTimeMillis,
) : RobotDriver {
    val protocol = RosbridgeProtocol(config)
    private val flow = MutableSharedFlow<RobotPose>(extraBufferCapacity = 256)
    override val poses: SharedFlow<RobotPose> = flow.asSharedFlow()
    private val goals = ConcurrentHashMap<String, CompletableDeferred<Unit>>()
    private val goalIds = AtomicLong()
    @Volatile private var socket: WebSocketConnection? = null
    @Volatile private var reachTarget: Pair<Pair<Double, Double>, CompletableDeferred<Unit>>? = null
    @Volatile private var activeGoal: String? = null

    /** The last pose received. */
    @Volatile var lastPose: RobotPose? = null
        private set

    private val listener = object : WebSocketListener {
        override fun onMessage(text: String) = handle(protocol.decode(text))

        override fun onClosed(reason: String) {
            val e = RobotException("rosbridge connection closed: $reason")
            goals.values.forEach { it.completeExceptionally(e) }
            reachTarget?.second?.completeExceptionally(e)
            socket = null
        }
    }

    /** Opens the WebSocket and subscribes to the pose topic (idempotent). */
    fun connect() {
        if (socket != null) return
        val s = factory.connect(config.url, listener)
        socket = s
        s.send(protocol.subscribePose())
        if (config.goalMode == GoalMode.GOAL_POSE_TOPIC) s.send(protocol.advertiseGoal())
    }

    /** Handles one decoded message (public for the tests and for custom transports). */
    fun handle(msg: RosbridgeIncoming) {
        when (msg) {
            is RosbridgeIncoming.Pose -> {
                val p = RobotPose(clock(), msg.x, msg.y, config.floor, msg.heading)
                lastPose = p
                flow.tryEmit(p)
                reachTarget?.let { (target, done) ->
                    if (hypot(target.first - msg.x, target.second - msg.y) <= config.goalTolerance) done.complete(Unit)
                }
            }
            is RosbridgeIncoming.ActionResult -> {
                val d = goals.remove(msg.id) ?: return
                if (msg.ok && (msg.status == null || msg.status == RosbridgeProtocol.STATUS_SUCCEEDED)) {
                    d.complete(Unit)
                } else {
                    d.completeExceptionally(RobotException("goal ${msg.id} ended with status ${msg.status}"))
                }
            }
            else -> Unit
        }
    }

    private fun send(text: String) {
        val s = socket ?: throw RobotException("not connected to rosbridge at ${config.url}")
        if (!s.send(text)) throw RobotException("rosbridge at ${config.url} refused a message (socket closed)")
    }

    override suspend fun follow(waypoints: List<Waypoint>) {
        connect()
        for ((i, w) in waypoints.withIndex()) {
            val from = if (i > 0) waypoints[i - 1] else lastPose?.let { Waypoint("", it.x, it.y) } ?: w
            val yaw = if (from.x == w.x && from.y == w.y) lastPose?.heading ?: 0.0 else atan2(w.y - from.y, w.x - from.x)
            try {
                when (config.goalMode) {
                    GoalMode.NAV2_ACTION -> {
                        val id = "trailprint-goal-${goalIds.incrementAndGet()}"
                        val done = CompletableDeferred<Unit>()
                        goals[id] = done
                        activeGoal = id
                        send(protocol.sendActionGoal(id, w.x, w.y, yaw))
                        done.await()
                    }
                    GoalMode.GOAL_POSE_TOPIC -> {
                        val done = CompletableDeferred<Unit>()
                        reachTarget = Pair(Pair(w.x, w.y), done)
                        lastPose?.let { if (hypot(it.x - w.x, it.y - w.y) <= config.goalTolerance) done.complete(Unit) }
                        if (!done.isCompleted) send(protocol.publishGoal(w.x, w.y, yaw))
                        done.await()
                    }
                }
            } catch (e: kotlinx.coroutines.CancellationException) {
                stop()
                throw e
            } finally {
                activeGoal = null
                reachTarget = null
            }
        }
    }

    override fun stop() {
        val id = activeGoal
        if (id != null && config.goalMode == GoalMode.NAV2_ACTION) {
            socket?.send(protocol.cancelActionGoal(id))
            goals.remove(id)?.completeExceptionally(RobotException("goal $id cancelled"))
        }
        lastPose?.let { p ->
            if (config.goalMode == GoalMode.GOAL_POSE_TOPIC) socket?.send(protocol.publishGoal(p.x, p.y, p.heading))
        }
    }

    override fun close() {
        stop()
        socket?.let {
            it.send(protocol.unsubscribePose())
            it.close()
        }
        socket = null
    }
}
