package dev.trailprint.robot

import kotlinx.coroutines.flow.Flow

/** A planned waypoint: a vertex of the building and its position, metres. */
data class Waypoint(val vertexId: String, val x: Double, val y: Double, val floor: Long = 0)

/** Where the robot is: building coordinates, heading (radians, 0 = +x, counter-clockwise). */
data class RobotPose(val timestampMs: Long, val x: Double, val y: Double, val floor: Long, val heading: Double)

/**
 * A robot that drives a planned walk and reports where it is. The app feeds the poses,
 * and the Wi-Fi scans taken on the way, to a robot survey session.
 *
 * Implementations: [SimulatedRobot] (demo and tests) and [RosbridgeRobotDriver] (a ROS 2
 * robot through rosbridge).
 */
interface RobotDriver : AutoCloseable {
    /** Poses as the robot reports them (hot; collect before calling [follow]). */
    val poses: Flow<RobotPose>

    /**
     * Drives through [waypoints] in order and returns when the last one is reached.
     * Cancelling the calling coroutine stops the robot. Throws [RobotException] when the
     * robot reports that it cannot reach a waypoint.
     */
    suspend fun follow(waypoints: List<Waypoint>)

    /** Stops the robot where it is. */
    fun stop()

    override fun close() = stop()
}

/** The robot failed to reach a goal, or the link to it broke. */
class RobotException(message: String, cause: Throwable? = null) : Exception(message, cause)
