package dev.trailprint.testing

import dev.trailprint.demo.SimulatedWifi
import dev.trailprint.ffi.BuildingMap
import dev.trailprint.ffi.SessionProgress
import dev.trailprint.ffi.SessionSummary
import dev.trailprint.ffi.SurveySession
import dev.trailprint.ffi.WifiReading
import dev.trailprint.robot.SimulatedRobot
import dev.trailprint.robot.SimulatedRobotConfig
import dev.trailprint.robot.Waypoint

/**
 * Drives a simulated robot (seed 2) along [walk] (vertex ids of [map], [lengthM] long) in
 * this session: a pose every second and a scan every second, at the speed that makes
 * about [scans] scans, from [t0]; [check] sees the progress every 20 scans. Finishes the
 * session and returns its summary (the session stays open).
 */
fun SurveySession.driveRobotAlong(
    map: BuildingMap,
    walk: List<String>,
    lengthM: Double,
    scans: Int,
    t0: Long = 1_700_000_000_000L,
    check: (SessionProgress) -> Unit = {},
): SessionSummary {
    val byId = map.vertices.associateBy { it.id }
    val waypoints = walk.map { id -> byId.getValue(id).let { Waypoint(id, it.x, it.y, it.floor) } }
    val wifi = SimulatedWifi(map, seed = 2)
    val robot = SimulatedRobot(
        SimulatedRobotConfig(speed = lengthM / scans, poseIntervalMs = 1000, seed = 2, timeScale = 0.0, startTimeMs = t0),
    )
    var lastScan: Long? = null
    var scanned = 0
    var t = t0
    for (p in robot.trajectory(waypoints)) {
        t = p.timestampMs
        robotPose(t, p.x, p.y, p.floor)
        if (lastScan == null || t - lastScan >= 1000) {
            lastScan = t
            val scan = wifi.scanAt(t, p.x, p.y, p.floor)
            scan(t, scan.readings.map { WifiReading(it.bssid, it.rssDbm.toDouble()) })
            if (++scanned % 20 == 0) check(progress())
        }
    }
    return finish(t + 1000)
}
