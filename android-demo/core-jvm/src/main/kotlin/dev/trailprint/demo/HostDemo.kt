package dev.trailprint.demo

import dev.trailprint.PlanEvent
import dev.trailprint.Trailprint
import dev.trailprint.ffi.BuildingMap
import dev.trailprint.ffi.PlanAlgorithm
import dev.trailprint.ffi.PlanRequest
import dev.trailprint.ffi.PlanSummary
import dev.trailprint.ffi.Position
import dev.trailprint.ffi.SessionSummary
import dev.trailprint.ffi.SurveyorProfile
import dev.trailprint.ffi.defaultHumanProfile
import dev.trailprint.ffi.defaultRobotProfile
import dev.trailprint.robot.SimulatedRobot
import dev.trailprint.robot.SimulatedRobotConfig
import dev.trailprint.survey.SurveyController
import java.io.File
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.flow.takeWhile
import kotlinx.coroutines.launch
import kotlinx.coroutines.runBlocking

/** What a simulated survey did. */
data class DemoSurveyResult(
    val sessionId: Long,
    val summary: SessionSummary,
    val offRouteCheckIns: Int,
    val replans: Int,
    val csvLines: Int,
    /** Wall-clock time the controller took per step and per scan event, ms (human survey). */
    val stepHandlingMs: Double = 0.0,
    val scanHandlingMs: Double = 0.0,
)

/**
 * The end-to-end scenarios of the host demo, against the real native library: plan on a
 * building, walk the plan as a simulated person (steps, scans, check-ins, one wrong turn
 * that the session notices and replans around), and drive a plan with the simulated
 * robot. The tests run them too.
 */
class DemoScenarios(private val api: Trailprint, private val log: (String) -> Unit = ::println) {
    suspend fun plan(buildingId: Long, start: String, end: String, budgetM: Double, surveyor: SurveyorProfile, algorithm: PlanAlgorithm = PlanAlgorithm.AUTO, timeLimitS: Double? = 2.0): PlanSummary {
        var done: PlanSummary? = null
        var lastPct = -10
        api.plan(PlanRequest(buildingId, start, end, budgetM, surveyor, algorithm, 1uL, timeLimitS)).collect { ev ->
            when (ev) {
                is PlanEvent.Progress -> {
                    val pct = (ev.progress.fraction * 100).toInt()
                    if (pct >= lastPct + 10) {
                        lastPct = pct
                        log("  plan %3d%%  %-28s best %s".format(pct, ev.progress.message.take(28), ev.progress.bestUtilityNats?.let { "%.2f nats".format(it) } ?: "-"))
                    }
                }
                is PlanEvent.Done -> done = ev.plan
            }
        }
        val p = done!!
        log("  planned ${p.algorithm}: %.1f m of %.0f m, %d samples, %.2f nats, %d vertices".format(p.lengthM, p.budgetM, p.samples.toLong(), p.utilityNats, p.walk.size))
        return p
    }

    /**
     * A person walks [plan]: at the [wrongTurnAtLeg]-th check-in they take a wrong corridor
     * and check in where they ended up; the session goes off-route and replans.
     */
    suspend fun humanSurvey(map: BuildingMap, plan: PlanSummary, wrongTurnAtLeg: Int? = 2, seed: Long = 1): DemoSurveyResult {
        val profile = defaultHumanProfile()
        val session = api.startSession(plan.id, profile)
        val wifi = SimulatedWifi(map, seed)
        val walker = SimulatedWalker(wifi, stepLength = 0.75)
        val pos = map.vertices.associate { it.id to Position(it.x, it.y, it.floor) }
        val neighbours = map.edges.flatMap { listOf(it.a to it.b, it.b to it.a) }.groupBy({ it.first }, { it.second })
        pos.getValue(plan.walk.first()).let { walker.placeAt(it.x, it.y, it.floor) }
        val scope = CoroutineScope(Dispatchers.IO)
        val c = SurveyController(session, scope, Dispatchers.IO, clock = { walker.tMs })
        c.refresh()
        var checkIns = 0
        var offRoute = 0
        var current = plan.walk.first()
        var legs = 0
        // What each event costs to handle (the CPU time a wake lock covers on a phone).
        var stepNs = 0L
        var steps = 0
        var scanNs = 0L
        var scans = 0
        suspend fun walk(target: String) {
            val p = pos.getValue(target)
            for (ev in walker.walkTo(p.x, p.y, p.floor)) {
                val t0 = System.nanoTime()
                when (ev) {
                    is WalkEvent.Step -> c.step(ev.tMs).also { stepNs += System.nanoTime() - t0; steps++ }
                    is WalkEvent.Scan -> c.scan(ev.scan).also { scanNs += System.nanoTime() - t0; scans++ }
                }
            }
            current = target
        }
        suspend fun checkIn(target: String, planned: String) {
            walker.pauseFor(1500)
            val ack = c.checkIn(target, walker.tMs) ?: error("check-in at $target rejected: ${c.state.value.error}")
            checkIns++
            if (ack.wentOffRoute) {
                offRoute++
                log("  off route at $target (planned $planned): ${if (ack.replanSeq != null) "replanned" else "replan failed: ${ack.replanError}"}")
            }
            val pr = c.state.value.progress!!
            log("  check-in %-4s %3.0f%%  walked %5.1f m  %3d samples  %.2f nats  %s".format(target, pr.fractionDone * 100, pr.walkedM, pr.samples.toLong(), pr.collectedUtilityNats, c.state.value.guidance?.message ?: ""))
        }
        while (true) {
            // The walk still ahead, as the session sees it (it changes after a replan).
            val ahead = session.routeAhead()
            if (ahead.isEmpty()) break
            for ((i, w) in ahead.withIndex()) {
                if (++legs > 1000) error("the simulated walk does not end")
                if (wrongTurnAtLeg != null && checkIns >= wrongTurnAtLeg && offRoute == 0) {
                    // A corridor the rest of the walk never takes (if there is one here).
                    val wrong = neighbours[current].orEmpty().firstOrNull { it != w.vertex && it !in ahead.map { a -> a.vertex } }
                    if (wrong != null) {
                        walk(wrong)
                        checkIn(wrong, w.vertex)
                        break
                    }
                }
                walk(w.vertex)
                if (w.checkIn || i == ahead.lastIndex) {
                    checkIn(w.vertex, w.vertex)
                    break
                }
            }
        }
        val summary = c.finish(walker.tMs + 1000) ?: error("finish rejected: ${c.state.value.error}")
        val csv = session.exportCsv()
        log("  finished: %.1f m, %d samples, %d check-ins, %d replans, %.2f of %.2f planned nats, step %.3f m".format(summary.walkedM, summary.samples.toLong(), summary.checkIns.toInt(), summary.replans.toInt(), summary.collectedUtilityNats, summary.plannedUtilityNats, summary.stepLengthM))
        scope.coroutineContext[kotlinx.coroutines.Job]?.cancel()
        val id = session.id()
        session.close()
        val stepMs = if (steps > 0) stepNs / 1e6 / steps else 0.0
        val scanMs = if (scans > 0) scanNs / 1e6 / scans else 0.0
        log("  event handling on this host: %d steps, %.2f ms each; %d scans, %.2f ms each".format(steps, stepMs, scans, scanMs))
        return DemoSurveyResult(id, summary, offRoute, summary.replans.toInt(), csv.lines().count { it.isNotBlank() }, stepMs, scanMs)
    }

    /** The simulated robot drives [plan], scanning every second of simulated time. */
    suspend fun robotSurvey(map: BuildingMap, plan: PlanSummary, seed: Long = 2): DemoSurveyResult {
        val profile = defaultRobotProfile()
        val session = api.startSession(plan.id, profile)
        val wifi = SimulatedWifi(map, seed)
        val robot = SimulatedRobot(SimulatedRobotConfig(speed = 0.5, poseIntervalMs = 500, poseNoise = 0.02, seed = seed, timeScale = 0.0, startTimeMs = 1_700_000_000_000))
        val scope = CoroutineScope(Dispatchers.IO)
        val c = SurveyController(session, scope, Dispatchers.IO, clock = { robot.clockMs })
        c.refresh()
        val pos = map.vertices.associate { it.id to Position(it.x, it.y, it.floor) }
        val waypoints = c.waypointsAhead(pos).let { ahead ->
            val first = pos.getValue(plan.walk.first())
            listOf(dev.trailprint.robot.Waypoint(plan.walk.first(), first.x, first.y, first.floor)) + ahead
        }
        var lastScan: Long? = null
        var poses = 0
        var rejected = 0
        // Every pose goes to the session, and a scan whenever a second has passed: the
        // trajectory is computed up front, so the session sees it in order.
        for (p in robot.trajectory(waypoints)) {
            c.robotPose(p)
            poses++
            if (lastScan == null || p.timestampMs - lastScan!! >= 1000) {
                lastScan = p.timestampMs
                if (c.scan(wifi.scanAt(p.timestampMs, p.x, p.y, p.floor)) == null && rejected++ == 0) {
                    log("  scan rejected: ${c.state.value.error}")
                }
            }
            if (poses % 100 == 0) {
                val pr = c.state.value.progress!!
                log("  robot %3.0f%%  walked %5.1f m  %3d samples  %.2f nats".format(pr.fractionDone * 100, pr.walkedM, pr.samples.toLong(), pr.collectedUtilityNats))
            }
        }
        val end = waypoints.last()
        val summary = c.finish(robot.trajectory(waypoints).last().timestampMs + 1000) ?: error("finish rejected: ${c.state.value.error}")
        log("  robot finished at ${end.vertexId}: %.1f m, %d poses, %d samples, %.2f of %.2f planned nats".format(summary.walkedM, poses, summary.samples.toLong(), summary.collectedUtilityNats, summary.plannedUtilityNats))
        scope.coroutineContext[kotlinx.coroutines.Job]?.cancel()
        val csv = session.exportCsv()
        val id = session.id()
        session.close()
        return DemoSurveyResult(id, summary, 0, summary.replans.toInt(), csv.lines().count { it.isNotBlank() })
    }
}

/**
 * Host demo: `HostDemoKt [building.json] [database]`. Imports the building, plans a human
 * walk and surveys it with a simulated person, then plans a robot walk and drives it with
 * the simulated robot, printing progress.
 */
fun main(args: Array<String>) = runBlocking {
    val repo = File(System.getProperty("trailprint.repo") ?: ".")
    val building = File(args.getOrNull(0) ?: File(repo, "android-demo/demo/demo-building.json").path)
    val dbFile = args.getOrNull(1)?.let(::File) ?: File.createTempFile("trailprint-demo", ".db").also { it.delete(); it.deleteOnExit() }
    println("Trailprint host demo: ${building.path} -> ${dbFile.path}")
    Trailprint.open(dbFile.path).use { api ->
        val b = api.importBuilding(building.readText(), building.name, replace = true)
        val map = api.map(b.id)
        println("building ${b.name}: ${b.vertices} vertices, ${b.edges} edges, ${b.pilot} pilot points")
        val start = map.vertices.first().id
        val end = map.vertices.first { it.id != start && map.edges.any { e -> e.a == it.id || e.b == it.id } }.id
        val demo = DemoScenarios(api)
        println("human survey: plan $start -> $start, 60 m")
        val humanPlan = demo.plan(b.id, start, start, 60.0, defaultHumanProfile())
        val human = demo.humanSurvey(map, humanPlan)
        println("  exported ${human.csvLines - 1} fingerprints as CSV")
        println("robot survey: plan $start -> $end, 40 m")
        val robotPlan = demo.plan(b.id, start, end, 40.0, defaultRobotProfile())
        val robot = demo.robotSurvey(map, robotPlan)
        println("  exported ${robot.csvLines - 1} fingerprints as CSV")
        println("done: sessions ${human.sessionId} (human) and ${robot.sessionId} (robot) in ${dbFile.path}")
    }
}
