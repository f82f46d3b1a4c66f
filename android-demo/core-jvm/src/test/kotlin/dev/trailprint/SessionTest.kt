package dev.trailprint

import dev.trailprint.demo.DemoScenarios
import dev.trailprint.demo.SimulatedWifi
import dev.trailprint.ffi.BuildingMap
import dev.trailprint.ffi.PlanAlgorithm
import dev.trailprint.ffi.SessionOptions
import dev.trailprint.ffi.SessionProgress
import dev.trailprint.ffi.SessionStatus
import dev.trailprint.ffi.SessionSummary
import dev.trailprint.ffi.SurveySession
import dev.trailprint.ffi.TrailprintException
import dev.trailprint.ffi.TrailprintStore
import dev.trailprint.ffi.WifiReading
import dev.trailprint.ffi.defaultHumanProfile
import dev.trailprint.ffi.defaultRobotProfile
import dev.trailprint.ffi.defaultSessionOptions
import dev.trailprint.survey.LifecycleState
import dev.trailprint.survey.SurveyController
import dev.trailprint.survey.SurveyLive
import dev.trailprint.survey.SurveyNotificationPolicy
import dev.trailprint.survey.SurveyPhase
import dev.trailprint.testing.ScratchDir
import dev.trailprint.testing.TestData
import dev.trailprint.testing.driveRobotAlong
import dev.trailprint.testing.greedyPlan
import dev.trailprint.ui.FinishState
import dev.trailprint.ui.SurveyUiState
import java.io.File
import java.util.concurrent.ConcurrentLinkedQueue
import kotlin.concurrent.thread
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith
import kotlin.test.assertNotNull
import kotlin.test.assertNull
import kotlin.test.assertTrue
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.runBlocking

class SessionTest : ScratchDir("trailprint-session-test") {
    private val t0 = 1_700_000_000_000L

    /** A store with the demo building and a straight greedy plan c00 -> c06 (9 m). */
    private fun setUp(path: String, budget: Double = 9.0, end: String = "c06", robot: Boolean = false): Triple<TrailprintStore, Long, Long> {
        val store = TrailprintStore.open(path)
        val bid = store.importBuildingJson(TestData.demoBuildingJson, "demo", false).id
        val profile = if (robot) defaultRobotProfile() else defaultHumanProfile()
        val plan = store.greedyPlan(bid, end, budget, profile)
        return Triple(store, bid, plan.id)
    }

    /**
     * Runs [test] on a new session of [setUp]'s plan (with [budget] and [end]) in the
     * database file [name]; closes the session and the store after.
     */
    private inline fun withSession(name: String, budget: Double = 9.0, end: String = "c06", test: (TrailprintStore, SurveySession) -> Unit) {
        val (store, _, planId) = setUp(File(dir, name).path, budget, end)
        store.use { it.startSession(planId, defaultHumanProfile(), null).use { s -> test(it, s) } }
    }

    private fun readings(i: Int) = listOf(WifiReading("aa:aa", -50.0 - i), WifiReading("bb:bb", -70.0 + i))

    @Test
    fun aHumanSessionWithStepsScansCheckInsAnOffRouteCheckInAndAReplan() {
        withSession("h.db", budget = 20.0, end = "c10") { _, s ->
            assertEquals(SessionStatus.ACTIVE, s.status())
            assertEquals("c01", s.guidance().nextVertex)
            var t = t0
            s.checkIn(t, "c00")
            // Walk 3 m (about 4 steps) with a scan, check in at c02.
            repeat(4) { t += 600; s.step(t, 1u) }
            val scan = s.scan(t + 10, readings(1))
            assertNotNull(scan.sample)
            assertTrue(scan.sample!!.rss.containsKey("aa:aa"))
            t += 1000
            val on = s.checkIn(t, "c02")
            assertTrue(!on.offRoute, "c02 is on the walk")
            // A wrong turn: into the side corridor? c02 has no side branch; go back to c01 instead.
            repeat(2) { t += 600; s.step(t, 1u) }
            t += 1000
            val off = s.checkIn(t, "c01")
            assertTrue(off.wentOffRoute, "checking in at c01 after c02 goes against the walk")
            // Automatic replanning is on: the session replanned (or says why not).
            assertTrue(off.replanSeq != null || off.replanError != null)
            val r = s.replan()
            assertEquals("c10", r.walk.last())
            assertTrue(r.lengthM <= r.budgetLeftM + 1e-6 || r.overBudget)
            assertEquals(r.walk.getOrNull(1), s.guidance().nextVertex)
            val p = s.progress()
            assertTrue(p.samples >= 1uL)
            assertTrue(p.collectedUtilityNats > 0, "${p.collectedUtilityNats}")
            assertTrue(p.replans >= 1u)
            assertTrue(p.uncertainty.size == 48)
            t += 1000
            val summary = s.finish(t)
            assertEquals(SessionStatus.FINISHED, summary.status)
            assertTrue(summary.checkIns >= 3u)
            val e = assertFailsWith<TrailprintException.Session> { s.scan(t + 1, readings(2)) }
            assertTrue("finish" in e.message!!.lowercase(), e.message)
            assertTrue(s.exportCsv().lines().size >= 2)
            assertTrue("aa:aa" in s.exportJson())
        }
    }

    @Test
    fun aSessionResumesFromAFreshStoreObject() {
        val db = File(dir, "r.db").path
        val (store, bid, planId) = setUp(db)
        val sid: Long
        val before: String
        store.use {
            val s = it.startSession(planId, defaultHumanProfile(), null)
            sid = s.id()
            var t = t0
            s.checkIn(t, "c00")
            repeat(5) { i -> t += 600; s.step(t, 1u); if (i % 2 == 0) s.scan(t + 1, readings(i)) }
            s.checkIn(t + 1000, "c03")
            before = s.progress().let { p -> "${p.walkedM} ${p.samples} ${p.collectedUtilityNats}" }
            s.close()
        }
        // Another store object, as after the app was killed.
        TrailprintStore.open(db).use { again ->
            assertEquals(listOf(sid), again.listSessions(bid).map { it.id })
            val s = again.resumeSession(sid)
            val p = s.progress()
            assertEquals(before, "${p.walkedM} ${p.samples} ${p.collectedUtilityNats}")
            assertEquals(3, s.samples().size)
            assertEquals("c04", s.guidance().nextVertex)
            // And it goes on.
            s.step(t0 + 10_000, 1u)
            assertEquals(SessionStatus.FINISHED, s.finish(t0 + 11_000).status)
            s.close()
        }
    }

    @Test
    fun rejectedEventsAreErrorsOfTheRightKind() {
        withSession("e.db") { store, s ->
            s.step(t0 + 1000, 1u)
            val back = assertFailsWith<TrailprintException> { s.step(t0, 1u) }
            assertTrue(back is TrailprintException.Session || back is TrailprintException.InvalidRequest, "$back")
            val unknown = assertFailsWith<TrailprintException> { s.checkIn(t0 + 2000, "nowhere") }
            assertTrue("nowhere" in unknown.message!!, unknown.message)
            val badRss = assertFailsWith<TrailprintException> { s.scan(t0 + 3000, listOf(WifiReading("x", 20.0))) }
            assertTrue("20" in badRss.message!!, badRss.message)
            val missing = assertFailsWith<TrailprintException.NotFound> { store.resumeSession(987654) }
            assertTrue("987654" in missing.message!!, missing.message)
            val noPlan = assertFailsWith<TrailprintException.NotFound> { store.startSession(424242, defaultHumanProfile(), null) }
            assertTrue("424242" in noPlan.message!!, noPlan.message)
        }
    }

    @Test
    fun aSessionIsSafeToUseFromSeveralThreads() {
        withSession("t.db") { _, s ->
            val seqs = ConcurrentLinkedQueue<Long>()
            val errors = ConcurrentLinkedQueue<Throwable>()
            // Every thread uses the same timestamp so order does not matter to the session.
            val threads = (0 until 4).map { k ->
                thread {
                    repeat(10) {
                        try {
                            seqs += s.step(t0, 1u).seq
                            s.progress()
                            s.guidance()
                        } catch (e: Throwable) {
                            errors += e
                        }
                    }
                }
            }
            threads.forEach { it.join() }
            assertTrue(errors.isEmpty(), "$errors")
            assertEquals(40, seqs.toSet().size)
        }
    }

    @Test
    fun theControllerKeepsEventTimesFromGoingBackwards() = runBlocking {
        withSession("c.db") { _, s ->
            var now = t0 + 5000
            val c = SurveyController(s, this, Dispatchers.IO, clock = { now })
            c.refresh()
            assertNotNull(c.checkIn("c00"))
            // A scan stamped before the last event is clamped, not rejected.
            val ack = c.scan(dev.trailprint.sensors.WifiScan(t0, listOf(dev.trailprint.sensors.WifiReading("aa", -60))))
            assertNotNull(ack, c.state.value.error)
            now += 600
            assertNotNull(c.step())
            assertEquals(3, c.state.value.track.size)
            c.finish()
            assertNotNull(c.state.value.summary)
            // After finish a step is rejected and shown as an error; nothing throws.
            assertNull(c.step(now + 1000))
            assertNotNull(c.state.value.error)
        }
    }

    @Test
    fun simulatedHumanAndRobotSurveysEndToEnd() = runBlocking {
        Trailprint.open(File(dir, "demo.db").path).use { api ->
            val bid = api.importBuilding(TestData.demoBuildingJson, "demo").id
            val map = api.map(bid)
            val log = mutableListOf<String>()
            val demo = DemoScenarios(api) { log += it }
            val humanPlan = demo.plan(bid, "c00", "c20", 50.0, defaultHumanProfile(), PlanAlgorithm.GREEDY, null)
            val human = demo.humanSurvey(map, humanPlan, wrongTurnAtLeg = 2)
            assertEquals(SessionStatus.FINISHED, human.summary.status)
            assertTrue(human.summary.samples > 3uL, "${human.summary}\n" + log.joinToString("\n"))
            assertEquals(1, human.offRouteCheckIns, log.joinToString("\n"))
            assertTrue(human.replans >= 1)
            assertTrue(human.summary.collectedUtilityNats > 0)
            val robotPlan = demo.plan(bid, "c00", "c20", 40.0, defaultRobotProfile(), PlanAlgorithm.GREEDY, null)
            val robot = demo.robotSurvey(map, robotPlan)
            assertEquals(SessionStatus.FINISHED, robot.summary.status)
            assertTrue(robot.summary.walkedM >= 30.0 - 1.0, "${robot.summary}")
            assertTrue(robot.summary.samples >= 40uL, "${robot.summary}")
            assertEquals(robot.summary.samples.toInt() + 1, robot.csvLines)
            // The UI state of a finished session.
            val sessions = api.sessions(bid)
            assertEquals(2, sessions.size)
            assertTrue(sessions.all { it.status == SessionStatus.FINISHED })
        }
    }

    /**
     * A new robot session of [planId] with [options], driven along the plan by the
     * simulated robot (seeded) slowly enough to take [scans] scans, one a second with
     * each pose; [check] sees the progress every 20 scans. Returns the summary and the
     * fingerprints the session stored.
     */
    private fun driveRobot(
        store: TrailprintStore,
        map: BuildingMap,
        planId: Long,
        options: SessionOptions?,
        scans: Int,
        check: (SessionProgress) -> Unit = {},
    ): Pair<SessionSummary, Int> = store.startSession(planId, defaultRobotProfile(), options).use { s ->
        val plan = store.getPlan(planId)
        s.driveRobotAlong(map, plan.walk, plan.lengthM, scans, t0, check) to s.samples().size
    }

    @Test
    fun aLongRobotSessionPastItsMemoryBudgetSaysItsInformationIsALowerBound() {
        // A robot walk to the far end of the building (greedy: some 80 m of a 300 m budget),
        // 640 scans along it (8 a metre): more than half of 1 MiB holds exactly (~280).
        val (store, bid, planId) = setUp(File(dir, "budget.db").path, budget = 300.0, end = "r34", robot = true)
        store.use {
            val map = store.buildingMap(bid)
            val blocks = mutableListOf<ULong>()
            var lowerBound: SessionProgress? = null
            val (bounded, boundedStored) = driveRobot(store, map, planId, defaultSessionOptions().copy(memoryBudgetMb = 1uL), scans = 640) { p ->
                assertTrue(p.samplesInFigures <= p.samples, "${p.samplesInFigures} of ${p.samples} in the figures")
                if (blocks.lastOrNull() != p.sampleBlock) blocks += p.sampleBlock
                if (p.sampleBlock > 1uL && lowerBound == null) lowerBound = p
            }
            assertEquals(1uL, blocks.firstOrNull(), "exact until the budget is reached: $blocks")
            assertTrue(blocks.zipWithNext().all { (a, b) -> b > a }, "$blocks")
            val p = assertNotNull(lowerBound, "the budget was never reached: $blocks")
            // What the surveyor sees while the survey runs: "≥" before the nats collected.
            val ui = SurveyUiState.of(map, null, bounded.sessionId, SurveyLive(progress = p), emptyList())
            assertTrue(ui.collectedIsLowerBound)
            assertEquals(p.collectedUtilityNats, ui.collectedNats)
            val running = SurveyNotificationPolicy.of(LifecycleState(phase = SurveyPhase.RUNNING, live = SurveyLive(progress = p)))
            assertTrue("≥ %.1f of".format(p.collectedUtilityNats) in running.text, running.text)
            val exactP = p.copy(sampleBlock = 1uL)
            assertTrue(!SurveyUiState.of(map, null, 1, SurveyLive(progress = exactP), emptyList()).collectedIsLowerBound)
            val exactText = SurveyNotificationPolicy.of(LifecycleState(phase = SurveyPhase.RUNNING, live = SurveyLive(progress = exactP))).text
            assertTrue("≥" !in exactText && "%.1f of".format(p.collectedUtilityNats) in exactText, exactText)

            assertEquals(SessionStatus.FINISHED, bounded.status)
            assertTrue(bounded.samples > 500uL, "${bounded.samples} samples")
            assertTrue(bounded.sampleBlock > 1uL, "${bounded.sampleBlock}")
            assertEquals(blocks.last(), bounded.sampleBlock)
            assertEquals(bounded.samples.toInt(), boundedStored, "every scan is still stored")
            val info = FinishState(bounded).lines().single { it.startsWith("Information:") }
            assertEquals(
                "Information: at least %.1f nats collected (one fingerprint in %d counted, memory budget), %.1f planned"
                    .format(bounded.collectedUtilityNats, bounded.sampleBlock.toLong(), bounded.plannedUtilityNats),
                info,
            )
            val done = SurveyNotificationPolicy.of(LifecycleState(phase = SurveyPhase.FINISHED, summary = bounded)).text
            assertTrue("≥ %.1f nats".format(bounded.collectedUtilityNats) in done, done)

            // The same walk within the default budget: exact, and at least as much information.
            val (exact, exactStored) = driveRobot(store, map, planId, null, scans = 640) { q ->
                assertEquals(1uL, q.sampleBlock)
                assertEquals(q.samples, q.samplesInFigures)
            }
            assertEquals(1uL, exact.sampleBlock)
            assertEquals(bounded.samples, exact.samples)
            assertEquals(boundedStored, exactStored)
            assertTrue(exact.collectedUtilityNats >= bounded.collectedUtilityNats, "${exact.collectedUtilityNats} < ${bounded.collectedUtilityNats}")
            assertTrue(bounded.collectedUtilityNats > 0.8 * exact.collectedUtilityNats, "${bounded.collectedUtilityNats} of ${exact.collectedUtilityNats}")
            // Fewer scans conditioned on: the radio map's uncertainty is an upper bound.
            assertTrue(bounded.meanStdDb >= exact.meanStdDb && bounded.maxStdDb >= exact.maxStdDb, "$bounded\n$exact")
            assertEquals(
                "Information: %.1f nats collected, %.1f planned".format(exact.collectedUtilityNats, exact.plannedUtilityNats),
                FinishState(exact).lines().single { it.startsWith("Information:") },
            )
            val exactDone = SurveyNotificationPolicy.of(LifecycleState(phase = SurveyPhase.FINISHED, summary = exact)).text
            assertTrue("≥" !in exactDone, exactDone)
        }
    }

    @Test
    fun simulatedWifiIsSeededAndWeakReadingsAreNotHeard() = runBlocking {
        Trailprint.inMemory().use { api ->
            val map = api.map(api.importBuilding(TestData.demoBuildingJson, "demo").id)
            val a = SimulatedWifi(map, seed = 5).scanAt(0, 1.0, 0.0, 0)
            val b = SimulatedWifi(map, seed = 5).scanAt(0, 1.0, 0.0, 0)
            assertEquals(a, b)
            assertTrue(a.readings.all { it.rssDbm in -95..0 })
            assertTrue(a.readings.isNotEmpty())
        }
    }
}
