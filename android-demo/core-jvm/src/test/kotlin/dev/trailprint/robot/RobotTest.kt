package dev.trailprint.robot

import dev.trailprint.json.Json
import dev.trailprint.json.double
import dev.trailprint.json.path
import java.util.Collections
import kotlin.math.PI
import kotlin.math.hypot
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith
import kotlin.test.assertIs
import kotlin.test.assertTrue
import kotlinx.coroutines.async
import kotlinx.coroutines.flow.toList
import kotlinx.coroutines.flow.take
import kotlinx.coroutines.runBlocking
import kotlinx.coroutines.withTimeout
import kotlinx.coroutines.yield

private val square = listOf(
    Waypoint("a", 0.0, 0.0), Waypoint("b", 2.0, 0.0), Waypoint("c", 2.0, 2.0), Waypoint("d", 0.0, 2.0),
)

class SimulatedRobotTest {
    @Test
    fun trajectoryDrivesAtConstantSpeedThroughEveryWaypoint() {
        val r = SimulatedRobot(SimulatedRobotConfig(speed = 0.5, poseIntervalMs = 500))
        val traj = r.trajectory(square, startMs = 1000)
        // 6 m at 0.5 m/s: 12 s.
        assertEquals(1000L, traj.first().timestampMs)
        assertEquals(13_000L, traj.last().timestampMs)
        for (w in square) assertTrue(traj.any { it.x == w.x && it.y == w.y }, "waypoint ${w.vertexId} missing")
        for ((a, b) in traj.zipWithNext()) {
            val dt = (b.timestampMs - a.timestampMs) / 1000.0
            assertTrue(dt > 0)
            assertTrue(hypot(b.x - a.x, b.y - a.y) <= 0.5 * dt + 1e-6, "faster than 0.5 m/s between $a and $b")
        }
        val third = traj.first { it.timestampMs == 6000L }
        assertEquals(2.0, third.x, 1e-9)
        assertEquals(0.5, third.y, 1e-9)
        assertEquals(PI / 2, third.heading, 1e-12)
    }

    @Test
    fun noiseIsSeeded() {
        val cfg = SimulatedRobotConfig(poseNoise = 0.1, seed = 42)
        assertEquals(SimulatedRobot(cfg).trajectory(square), SimulatedRobot(cfg).trajectory(square))
        val other = SimulatedRobot(cfg.copy(seed = 43)).trajectory(square)
        assertTrue(other != SimulatedRobot(cfg).trajectory(square))
    }

    @Test
    fun followEmitsThePosesAndAdvancesTheClock() = runBlocking {
        val r = SimulatedRobot(SimulatedRobotConfig(speed = 1.0, poseIntervalMs = 1000, timeScale = 0.0))
        val expected = r.trajectory(square)
        val got = async { r.poses.take(expected.size).toList() }
        yield()
        r.follow(square)
        assertEquals(expected, withTimeout(5000) { got.await() })
        assertEquals(6000L, r.clockMs)
    }
}

/** A WebSocket that records what is sent. */
private class FakeSocket : WebSocketConnection {
    val sent: MutableList<String> = Collections.synchronizedList(mutableListOf())
    var open = true
    override fun send(text: String): Boolean { if (open) sent += text; return open }
    override fun close() { open = false }
}

class RosbridgeTest {
    private fun amcl(x: Double, y: Double, qz: Double = 0.0, qw: Double = 1.0) = Json.encode(
        mapOf(
            "op" to "publish", "topic" to "/amcl_pose",
            "msg" to mapOf(
                "header" to mapOf("frame_id" to "map"),
                "pose" to mapOf(
                    "pose" to mapOf("position" to mapOf("x" to x, "y" to y, "z" to 0.0), "orientation" to mapOf("x" to 0.0, "y" to 0.0, "z" to qz, "w" to qw)),
                    "covariance" to List(36) { 0.0 },
                ),
            ),
        ),
    )

    @Test
    fun encodesANav2GoalInTheMapFrame() {
        val p = RosbridgeProtocol(RosbridgeConfig(mapX = 10.0, mapY = -5.0, mapYaw = PI / 2))
        val m = Json.parse(p.sendActionGoal("g1", 2.0, 0.0, 0.0))
        assertEquals("send_action_goal", m.path("op"))
        assertEquals("/navigate_to_pose", m.path("action"))
        assertEquals("nav2_msgs/action/NavigateToPose", m.path("action_type"))
        assertEquals("map", m.path("args", "pose", "header", "frame_id"))
        // Building (2, 0) rotated by 90 degrees is (0, 2), shifted: (10, -3).
        assertEquals(10.0, m.double("args", "pose", "pose", "position", "x")!!, 1e-12)
        assertEquals(-3.0, m.double("args", "pose", "pose", "position", "y")!!, 1e-12)
        assertEquals(kotlin.math.sin(PI / 4), m.double("args", "pose", "pose", "orientation", "z")!!, 1e-12)
        assertEquals(true, m.path("feedback"))
        val c = Json.parse(p.cancelActionGoal("g1"))
        assertEquals(mapOf("op" to "cancel_action_goal", "id" to "g1", "action" to "/navigate_to_pose"), c)
    }

    @Test
    fun encodesSubscriptionAndGoalPoseTopic() {
        val p = RosbridgeProtocol(RosbridgeConfig(poseTopic = "/odom", poseType = "nav_msgs/msg/Odometry", poseThrottleMs = 100))
        val s = Json.parse(p.subscribePose())
        assertEquals("subscribe", s.path("op"))
        assertEquals("/odom", s.path("topic"))
        assertEquals("nav_msgs/msg/Odometry", s.path("type"))
        assertEquals(100.0, s.path("throttle_rate"))
        val g = Json.parse(p.publishGoal(1.0, 2.0, PI))
        assertEquals("/goal_pose", g.path("topic"))
        assertEquals(1.0, g.double("msg", "pose", "position", "x"))
        assertEquals(1.0, g.double("msg", "pose", "orientation", "z")!!, 1e-12)
        assertEquals("geometry_msgs/msg/PoseStamped", Json.parse(p.advertiseGoal()).path("type"))
    }

    @Test
    fun decodesPosesResultsAndJunk() {
        val p = RosbridgeProtocol(RosbridgeConfig(mapX = 1.0, mapY = 1.0))
        val pose = assertIs<RosbridgeIncoming.Pose>(p.decode(amcl(3.0, 4.0, qz = kotlin.math.sin(PI / 4), qw = kotlin.math.cos(PI / 4))))
        assertEquals(2.0, pose.x, 1e-12)
        assertEquals(3.0, pose.y, 1e-12)
        assertEquals(PI / 2, pose.heading, 1e-12)
        val r = assertIs<RosbridgeIncoming.ActionResult>(p.decode("""{"op":"action_result","id":"g","action":"/navigate_to_pose","values":{},"status":4,"result":true}"""))
        assertEquals(RosbridgeIncoming.ActionResult("g", 4, true), r)
        val f = assertIs<RosbridgeIncoming.ActionFeedback>(p.decode("""{"op":"action_feedback","id":"g","values":{"distance_remaining":1.25}}"""))
        assertEquals(1.25, f.distanceRemaining)
        assertIs<RosbridgeIncoming.Other>(p.decode("not json"))
        assertIs<RosbridgeIncoming.Other>(p.decode("""{"op":"publish","topic":"/chatter","msg":{"data":"hi"}}"""))
    }

    @Test
    fun driverSendsOneGoalPerWaypointAndWaitsForEachResult() = runBlocking {
        val socket = FakeSocket()
        lateinit var listener: WebSocketListener
        val driver = RosbridgeRobotDriver({ _, l -> listener = l; socket }, RosbridgeConfig(), clock = { 77L })
        val poses = async { driver.poses.take(1).toList() }
        yield()
        val run = async { driver.follow(square.take(3)) }
        for (i in 0 until 3) {
            val goal = withTimeout(5000) {
                while (socket.sent.count { "send_action_goal" in it } <= i) yield()
                Json.parse(socket.sent.last { "send_action_goal" in it })
            }
            val id = goal.path("id") as String
            assertEquals(square[i].x, goal.double("args", "pose", "pose", "position", "x"))
            if (i == 0) listener.onMessage(amcl(0.1, 0.0))
            listener.onMessage("""{"op":"action_result","id":"$id","action":"/navigate_to_pose","values":{},"status":4,"result":true}""")
        }
        withTimeout(5000) { run.await() }
        assertEquals("subscribe", Json.parse(socket.sent.first()).path("op"))
        assertEquals(RobotPose(77L, 0.1, 0.0, 0, 0.0), withTimeout(5000) { poses.await() }.single())
    }

    @Test
    fun anAbortedGoalFailsTheWalk() = runBlocking {
        val socket = FakeSocket()
        lateinit var listener: WebSocketListener
        val driver = RosbridgeRobotDriver({ _, l -> listener = l; socket })
        val run = async { runCatching { driver.follow(square) } }
        val id = withTimeout(5000) {
            while (socket.sent.none { "send_action_goal" in it }) yield()
            Json.parse(socket.sent.last { "send_action_goal" in it }).path("id") as String
        }
        listener.onMessage("""{"op":"action_result","id":"$id","values":{},"status":6,"result":false}""")
        val e = assertFailsWith<RobotException> { withTimeout(5000) { run.await() }.getOrThrow() }
        assertTrue("status 6" in e.message!!, e.message)
    }

    @Test
    fun topicModeCountsAGoalReachedWithinTheTolerance() = runBlocking {
        val socket = FakeSocket()
        lateinit var listener: WebSocketListener
        val driver = RosbridgeRobotDriver({ _, l -> listener = l; socket }, RosbridgeConfig(goalMode = GoalMode.GOAL_POSE_TOPIC, goalTolerance = 0.3))
        val run = async { driver.follow(listOf(Waypoint("b", 2.0, 0.0))) }
        withTimeout(5000) { while (socket.sent.none { "\"publish\"" in it }) yield() }
        assertTrue(socket.sent.any { "\"advertise\"" in it })
        listener.onMessage(amcl(1.0, 0.0))
        yield()
        assertTrue(run.isActive)
        listener.onMessage(amcl(1.8, 0.1))
        withTimeout(5000) { run.await() }
    }
}
