package dev.trailprint

import dev.trailprint.ffi.SessionStatus
import dev.trailprint.ffi.defaultHumanProfile
import dev.trailprint.survey.ActiveSurvey
import dev.trailprint.survey.ActiveSurveyFile
import dev.trailprint.survey.AwakeMeter
import dev.trailprint.survey.LifecycleState
import dev.trailprint.survey.SurveyLifecycle
import dev.trailprint.survey.NotificationAction
import dev.trailprint.survey.RecordCheck
import dev.trailprint.survey.SurveyMode
import dev.trailprint.survey.SurveyNotificationPolicy
import dev.trailprint.survey.SurveyPhase
import dev.trailprint.testing.CountingWakeLock
import dev.trailprint.testing.FakeSensors
import dev.trailprint.testing.ScratchDir
import dev.trailprint.testing.TestData
import dev.trailprint.testing.greedyPlan
import java.io.File
import java.util.concurrent.atomic.AtomicLong
import kotlin.test.AfterTest
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith
import kotlin.test.assertFalse
import kotlin.test.assertNotNull
import kotlin.test.assertNull
import kotlin.test.assertTrue
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.SupervisorJob
import kotlinx.coroutines.cancel
import kotlinx.coroutines.flow.first
import kotlinx.coroutines.runBlocking
import kotlinx.coroutines.withTimeout

/** Issue 19: the survey's life (start, pause, resume, stop, process death) off Android. */
class LifecycleTest : ScratchDir("trailprint-lifecycle-test") {
    private val now = AtomicLong(1_700_000_000_000L)
    private val scopes = mutableListOf<CoroutineScope>()
    private val apis = mutableListOf<Trailprint>()

    @AfterTest
    fun cleanUp() {
        scopes.forEach { it.cancel() }
        apis.forEach { it.close() }
    }

    /** A "process": its own store object on the database file, its own scope and sensors. */
    private inner class Process(db: File, val sensors: FakeSensors = FakeSensors { now.get() }, lock: CountingWakeLock = CountingWakeLock()) {
        val api = Trailprint(dev.trailprint.ffi.TrailprintStore.open(db.path)).also { apis += it }
        val scope = CoroutineScope(SupervisorJob() + Dispatchers.Default).also { scopes += it }
        val wakeLock = lock
        val lifecycle = SurveyLifecycle(api, ActiveSurveyFile(File(dir, "active.json")), sensors, scope, lock, Dispatchers.IO, clock = { now.get() })

        /** Starts a survey of [planId] and waits until it runs. */
        suspend fun startRunning(planId: Long, mode: SurveyMode = SurveyMode.HUMAN): ActiveSurvey {
            val active = lifecycle.start(planId, mode)
            await("running") { it.phase == SurveyPhase.RUNNING }
            return active
        }

        /** Waits until the lifecycle's state satisfies [p]. */
        suspend fun await(what: String, p: (LifecycleState) -> Boolean): LifecycleState = try {
            withTimeout(20_000) { lifecycle.state.first(p) }
        } catch (e: Exception) {
            throw AssertionError("timed out waiting for $what; state: ${lifecycle.state.value}", e)
        }

        /** Waits until the running controller's state (the source of the lifecycle's) satisfies [p]. */
        suspend fun awaitLive(what: String, p: (dev.trailprint.survey.SurveyLive) -> Boolean) {
            val c = lifecycle.controller ?: throw AssertionError("no survey runs while waiting for $what")
            try {
                withTimeout(20_000) { c.state.first(p) }
            } catch (e: Exception) {
                throw AssertionError("timed out waiting for $what; live: ${c.state.value}", e)
            }
        }

        /** One step, [ms] after the last event, acknowledged. */
        suspend fun step(ms: Long = 600) {
            val seq = lifecycle.controller!!.state.value.lastAck?.seq ?: 0
            now.addAndGet(ms)
            sensors.step()
            awaitLive("step ack after seq $seq") { (it.lastAck?.seq ?: 0) > seq }
        }

        /** One completed scan, acknowledged with a fingerprint. */
        suspend fun scan(i: Int) {
            val n = lifecycle.controller!!.state.value.progress?.samples ?: 0uL
            now.addAndGet(100)
            sensors.scan(now.get(), "aa:aa" to -50 - i, "bb:bb" to -70 + i)
            awaitLive("sample ${n + 1uL}") { (it.progress?.samples ?: 0uL) > n }
        }
    }

    /** Waits (polling) until [cond] holds: for conditions outside the lifecycle's state. */
    private suspend fun poll(what: String, cond: () -> Boolean) {
        try {
            withTimeout(20_000) { while (!cond()) kotlinx.coroutines.delay(5) }
        } catch (e: Exception) {
            throw AssertionError("timed out waiting for $what", e)
        }
    }

    /** A database file [name] in [dir] with the demo building and a plan c00 -> c06: the file and the plan's id. */
    private fun planOn(name: String, robot: Boolean = false): Pair<File, Long> {
        val db = File(dir, name)
        val planId = dev.trailprint.ffi.TrailprintStore.open(db.path).use { store ->
            val bid = store.importBuildingJson(TestData.demoBuildingJson, "demo", false).id
            val profile = if (robot) dev.trailprint.ffi.defaultRobotProfile() else defaultHumanProfile()
            store.greedyPlan(bid, profile = profile).id
        }
        return db to planId
    }

    @Test
    fun aSurveyKilledMidWalkCarriesOnInANewProcessWithNothingLost() = runBlocking {
        val (db, planId) = planOn("kill.db")
        val first = Process(db)
        val active = first.lifecycle.start(planId, SurveyMode.HUMAN)
        first.await("running") { it.phase == SurveyPhase.RUNNING && it.live.guidance != null }
        poll("steps and scans listened to") { first.sensors.listening.get() >= 2 }
        assertNotNull(first.lifecycle.controller!!.checkIn("c00", now.get()))
        repeat(4) { first.step() }
        first.scan(1)
        now.addAndGet(1000)
        assertNotNull(first.lifecycle.controller!!.checkIn("c02", now.get()))
        repeat(2) { first.step() }
        first.scan(2)
        assertTrue(first.sensors.scanRequests.get() >= 1, "scans are requested while steps are handled")
        // What the session has acknowledged (it is on disk) at the moment of the kill.
        val before = first.lifecycle.controller!!.session.progress()
        val samplesBefore = first.lifecycle.controller!!.session.samples()

        // The process dies: its coroutines stop mid-survey; nothing is finished or closed.
        first.scope.cancel()

        val second = Process(db)
        val restored = second.lifecycle.restore()
        assertEquals(active, restored)
        val back = second.await("restored") { it.phase == SurveyPhase.RUNNING && it.live.progress != null }
        assertNotNull(back.message, "the surveyor is told the survey carried on")
        val p = back.live.progress!!
        assertEquals(before.walkedM, p.walkedM)
        assertEquals(before.samples, p.samples)
        assertEquals(before.collectedUtilityNats, p.collectedUtilityNats)
        assertEquals(samplesBefore.map { it.seq to it.rss }, second.lifecycle.controller!!.session.samples().map { it.seq to it.rss })
        assertEquals(samplesBefore.size, back.live.track.size, "the walked track is drawn again")
        poll("sensors back on") { second.sensors.listening.get() >= 2 }

        // And the walk goes on to the end.
        repeat(3) { second.step() }
        second.scan(3)
        now.addAndGet(1000)
        assertNotNull(second.lifecycle.controller!!.checkIn("c06", now.get()))
        val summary = second.lifecycle.stop()!!
        assertEquals(SessionStatus.FINISHED, summary.status)
        assertEquals(3uL, summary.samples)
        assertEquals(9uL, summary.steps)
        assertEquals(3u, summary.checkIns)
        assertEquals(SurveyPhase.FINISHED, second.lifecycle.state.value.phase)
        poll("sensors off after the survey") { second.sensors.listening.get() == 0 }
        assertFalse(File(dir, "active.json").exists())
        // A third start finds no survey to carry on.
        assertNull(Process(db).lifecycle.restore())
    }

    @Test
    fun aPausedSurveyRestartsPausedWithItsSensorsOffAndResumes() = runBlocking {
        val (db, planId) = planOn("pause.db")
        val first = Process(db)
        first.startRunning(planId)
        first.step()
        now.addAndGet(1000)
        first.lifecycle.pause()
        first.await("paused") { it.phase == SurveyPhase.PAUSED }
        poll("no sensor running while paused") { first.sensors.listening.get() == 0 }
        first.scope.cancel()

        val second = Process(db)
        assertNotNull(second.lifecycle.restore())
        second.await("paused after restart") { it.phase == SurveyPhase.PAUSED }
        kotlinx.coroutines.delay(50)
        assertEquals(0, second.sensors.listening.get(), "a paused survey restarts with its sensors off")
        assertEquals("Survey paused", SurveyNotificationPolicy.of(second.lifecycle.state.value).title)
        now.addAndGet(60_000)
        second.lifecycle.resume()
        second.await("running again") { it.phase == SurveyPhase.RUNNING }
        poll("sensors on") { second.sensors.listening.get() >= 2 }
        second.step()
        now.addAndGet(1000)
        val s = second.lifecycle.abort("test over")!!
        assertEquals(SessionStatus.ABORTED, s.status)
        assertEquals(2uL, s.steps)
        assertFalse(File(dir, "active.json").exists())
    }

    @Test
    fun oneSurveyAtATimeAndStaleOrCorruptRecordsAreReported() = runBlocking {
        val (db, planId) = planOn("one.db")
        val proc = Process(db)
        val a = proc.lifecycle.start(planId, SurveyMode.HUMAN)
        val again = assertFailsWith<AppException> { proc.lifecycle.start(planId, SurveyMode.HUMAN) }
        assertTrue("session ${a.sessionId}" in again.message!!, again.message)
        // Another process while the record exists is refused too.
        val other = Process(db)
        assertFailsWith<AppException> { other.lifecycle.start(planId, SurveyMode.HUMAN) }
        now.addAndGet(1000)
        proc.lifecycle.stop()

        // A record naming a session that has ended: cleared, with the reason.
        val file = ActiveSurveyFile(File(dir, "active.json"))
        file.write(a)
        assertNull(other.lifecycle.restore())
        assertEquals(SurveyPhase.FINISHED, other.lifecycle.state.value.phase)
        assertTrue("already ended" in other.lifecycle.state.value.message!!)
        assertFalse(file.file.exists())

        // A record naming a session that is not in the database.
        file.write(ActiveSurvey(987654, planId, SurveyMode.HUMAN, null, 0))
        assertNull(other.lifecycle.restore())
        assertTrue("987654" in other.lifecycle.state.value.message!!)

        // A corrupt record: reported naming the file and the field; forgetting it is possible.
        file.file.writeText("""{"format":"trailprint-active/1","session_id":"x","plan_id":1,"mode":"human","started_ms":0}""")
        assertNull(other.lifecycle.restore())
        val e = other.lifecycle.state.value.unreadableRecord
        assertTrue(e != null && "active.json" in e && "session_id" in e, e)
        other.lifecycle.forgetActive()
        assertNull(other.lifecycle.state.value.unreadableRecord)
        assertNull(other.lifecycle.restore())

        // A robot survey over plain ws:// to a host outside the local names is refused up front.
        val ws = assertFailsWith<AppException> { other.lifecycle.start(planId, SurveyMode.ROBOT, "ws://203.0.113.7:9090") }
        assertTrue("203.0.113.7" in ws.message!!, ws.message)
        // A plan made for a person is not driven by a robot.
        val kind = assertFailsWith<AppException> { other.lifecycle.start(planId, SurveyMode.ROBOT) }
        assertTrue("made for a person" in kind.message!!, kind.message)
        assertFalse(file.file.exists(), "a refused start records nothing")
    }

    @Test
    fun aCorruptRecordOffersForgetInsteadOfFailingAtEveryRestart() = runBlocking {
        val (db, planId) = planOn("corrupt.db")
        // A survey runs and the process dies; then the record is damaged (a truncated write
        // by a failing storage, a hand edit).
        val first = Process(db)
        val active = first.startRunning(planId)
        first.step()
        first.scope.cancel()
        val record = File(dir, "active.json")
        record.writeText(record.readText().take(30))

        // The app's launch sees it as a value, with the sentence above "Forget".
        val check = ActiveSurveyFile(record).check() as? RecordCheck.Unreadable
            ?: throw AssertionError("a truncated record reads as ${ActiveSurveyFile(record).check()}")
        assertTrue("active.json" in check.prompt && "Forget" in check.prompt, check.prompt)

        // Every restart of the service (START_STICKY) reports it and runs nothing: no
        // exception, no loop of failing restores.
        repeat(3) {
            val p = Process(db)
            assertNull(p.lifecycle.restore())
            val st = p.lifecycle.state.value
            assertEquals(SurveyPhase.IDLE, st.phase)
            assertNull(p.lifecycle.controller)
            assertTrue(st.unreadableRecord != null && "active.json" in st.unreadableRecord!!, st.unreadableRecord)
        }
        // A new survey is refused until the record is forgotten, and the refusal says so.
        val p = Process(db)
        val refused = assertFailsWith<AppException> { p.lifecycle.start(planId, SurveyMode.HUMAN) }
        assertTrue("forget it" in refused.message!!, refused.message)
        assertNotNull(p.lifecycle.state.value.unreadableRecord)
        p.lifecycle.forgetActive()
        assertNull(p.lifecycle.state.value.unreadableRecord)
        assertEquals(RecordCheck.None, ActiveSurveyFile(record).check())
        // What the forgotten survey collected is still in the database; a new survey starts.
        val old = p.api.sessions(p.api.plan(planId).buildingId).single { it.id == active.sessionId }
        assertEquals(SessionStatus.ACTIVE, old.status)
        assertTrue(old.lastSeq >= 1, "its events are kept: last seq ${old.lastSeq}")
        val next = p.lifecycle.start(planId, SurveyMode.HUMAN)
        assertTrue(next.sessionId != active.sessionId)
        assertEquals(RecordCheck.Found(next), ActiveSurveyFile(record).check())
        now.addAndGet(1000)
        assertNotNull(p.lifecycle.abort("test over"))
        Unit
    }

    @Test
    fun theNotificationFollowsTheSurveyAndProgressIsPostedAtMostOncePerSecond() = runBlocking {
        // Before the session's first progress: an indeterminate bar, no made-up figures.
        val starting = SurveyNotificationPolicy.of(LifecycleState(phase = SurveyPhase.RUNNING, active = ActiveSurvey(7, 3, SurveyMode.HUMAN, null, 0)))
        assertTrue(starting.indeterminate && starting.ongoing)
        assertEquals("Session 7: starting…", starting.text)

        val (db, planId) = planOn("notify.db")
        val proc = Process(db)
        proc.lifecycle.start(planId, SurveyMode.HUMAN)
        val s0 = proc.await("running with progress") { it.phase == SurveyPhase.RUNNING && it.live.progress != null }
        val n0 = SurveyNotificationPolicy.of(s0)
        assertEquals("Survey in progress", n0.title)
        assertEquals(listOf(NotificationAction.PAUSE, NotificationAction.FINISH), n0.actions)
        assertTrue(n0.ongoing && !n0.indeterminate)
        assertTrue("0 fingerprints" in n0.text, n0.text)
        assertNull(SurveyNotificationPolicy.delayBeforePost(n0, n0, 0, 10), "nothing new, nothing posted")
        assertEquals(0L, SurveyNotificationPolicy.delayBeforePost(null, n0, 0, 10), "the first one at once")

        assertNotNull(proc.lifecycle.controller!!.checkIn("c00", now.get()))
        repeat(3) { proc.step() }
        proc.scan(1)
        val s1 = proc.await("one fingerprint") { (it.live.progress?.samples ?: 0uL) >= 1uL }
        val n1 = SurveyNotificationPolicy.of(s1)
        val p1 = s1.live.progress!!
        assertEquals((p1.fractionDone * 1000).toInt(), n1.progress)
        assertTrue(n1.progress > n0.progress, "walking moves the bar: ${n0.progress} -> ${n1.progress}")
        assertTrue("1 fingerprints" in n1.text && "%.1f".format(p1.collectedUtilityNats) in n1.text, n1.text)
        // Progress only: once per second at most; the wait is what is left of the second.
        assertEquals(700L, SurveyNotificationPolicy.delayBeforePost(n0, n1, postedAtMs = 1000, nowMs = 1300))
        assertEquals(0L, SurveyNotificationPolicy.delayBeforePost(n0, n1, postedAtMs = 1000, nowMs = 2500))

        now.addAndGet(1000)
        proc.lifecycle.pause()
        val n2 = SurveyNotificationPolicy.of(proc.await("paused") { it.phase == SurveyPhase.PAUSED })
        assertEquals("Survey paused", n2.title)
        assertEquals(listOf(NotificationAction.RESUME, NotificationAction.FINISH), n2.actions)
        assertEquals(0L, SurveyNotificationPolicy.delayBeforePost(n1, n2, postedAtMs = 1000, nowMs = 1001), "a new phase is posted at once")
        // A rejected event is the second line, posted at once.
        val err = SurveyNotificationPolicy.of(s1.copy(live = s1.live.copy(error = "scan rejected: session paused")))
        assertEquals("scan rejected: session paused", err.subText)
        assertEquals(0L, SurveyNotificationPolicy.delayBeforePost(n1, err, postedAtMs = 1000, nowMs = 1001))

        now.addAndGet(1000)
        proc.lifecycle.resume()
        now.addAndGet(1000)
        val summary = proc.lifecycle.stop()!!
        val done = SurveyNotificationPolicy.of(proc.lifecycle.state.value)
        assertEquals("Survey finished", done.title)
        assertTrue(done.actions.isEmpty() && !done.ongoing, "a finished survey's notification can be swiped away")
        assertTrue("${summary.samples} fingerprints" in done.text, done.text)
    }

    @Test
    fun aRobotSurveyDrivesOnAfterARestart() = runBlocking {
        val (db, planId) = planOn("robot.db", robot = true)
        val first = Process(db)
        first.startRunning(planId, SurveyMode.ROBOT)
        first.awaitLive("three poses") { it.track.size >= 3 }
        first.scope.cancel()
        val acked = first.lifecycle.controller!!.session.progress().walkedM
        now.addAndGet(60_000) // the restart takes a while; the new robot's clock starts later

        val second = Process(db)
        assertEquals(SurveyMode.ROBOT, second.lifecycle.restore()!!.mode)
        second.await("restored") { it.phase == SurveyPhase.RUNNING }
        val start = second.lifecycle.controller!!.state.value.track.size
        second.awaitLive("the robot drives again") { it.track.size >= start + 3 }
        now.addAndGet(10_000)
        val summary = second.lifecycle.stop()!!
        assertEquals(SessionStatus.FINISHED, summary.status)
        assertTrue(summary.walkedM > acked, "walked ${summary.walkedM} m after ${acked} m before the restart")
    }

    @Test
    fun theCpuIsHeldAwakeOnlyWhileAnEventIsHandled() = runBlocking {
        val (db, planId) = planOn("awake.db")
        val lock = CountingWakeLock()
        val proc = Process(db, lock = lock)
        proc.startRunning(planId)
        assertFalse(lock.held, "not held between events")
        // An ack is published from inside its hold; the release follows at once.
        suspend fun released() = withTimeout(5_000) { while (lock.held) kotlinx.coroutines.delay(1) }
        repeat(5) {
            proc.step()
            released()
        }
        proc.scan(1)
        released()
        assertTrue(lock.acquires.get() >= 6, "one hold per event at least: ${lock.acquires.get()}")
        assertEquals(lock.acquires.get(), lock.releases.get())
        assertTrue(lock.timeouts.all { it in 1..60_000 }, "every hold has a timeout: ${lock.timeouts}")
        // A rejected event releases the lock too.
        now.addAndGet(1000)
        proc.lifecycle.stop()
        val c = dev.trailprint.survey.SurveyController(
            proc.api.resumeSession(proc.lifecycle.state.value.summary!!.sessionId), proc.scope, Dispatchers.IO, { now.get() },
            awake = AwakeMeter(lock, { now.get() }),
        )
        assertNull(c.step())
        assertNotNull(c.state.value.error)
        assertFalse(lock.held)
        assertEquals(lock.acquires.get(), lock.releases.get())
        c.session.close()
    }

    @Test
    fun theAwakeMeterCountsOverlappingHoldsOnceAndMeasuresHeldTime() = runBlocking {
        val lock = CountingWakeLock()
        val t = AtomicLong(0)
        val meter = AwakeMeter(lock, { t.get() }, timeoutMs = 5000)
        meter.held {
            assertTrue(lock.held)
            t.addAndGet(30)
            meter.held { t.addAndGet(20) } // nested: the lock stays, acquired once
            assertTrue(lock.held)
        }
        assertFalse(lock.held)
        t.addAndGet(950)
        assertFailsWith<IllegalStateException> { meter.held { t.addAndGet(10); error("handler failed") } }
        assertFalse(lock.held, "released when the handler throws")
        val s = meter.summary()
        assertEquals(2, lock.acquires.get())
        assertEquals(3L, s.holds)
        assertEquals(60L, s.heldMs)
        assertEquals(1010L, s.elapsedMs)
        assertEquals(listOf(5000L, 5000L), lock.timeouts)
        assertTrue(s.message().startsWith("CPU kept awake 5.9%"), s.message())
    }
}
