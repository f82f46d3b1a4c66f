package dev.trailprint

import dev.trailprint.ffi.PlanAlgorithm
import dev.trailprint.ffi.PlanListener
import dev.trailprint.ffi.PlanProgress
import dev.trailprint.ffi.PlanRequest
import dev.trailprint.ffi.TrailprintException
import dev.trailprint.ffi.TrailprintStore
import dev.trailprint.ffi.defaultHumanProfile
import dev.trailprint.ffi.defaultRobotProfile
import dev.trailprint.testing.ScratchDir
import dev.trailprint.testing.TestData
import dev.trailprint.ui.BudgetUnit
import dev.trailprint.ui.PlanModel
import dev.trailprint.ui.PlanState
import dev.trailprint.ui.Profile
import java.io.File
import java.util.concurrent.CopyOnWriteArrayList
import java.util.concurrent.CountDownLatch
import java.util.concurrent.TimeUnit
import kotlin.concurrent.thread
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith
import kotlin.test.assertIs
import kotlin.test.assertNotNull
import kotlin.test.assertNull
import kotlin.test.assertTrue
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.flow.first
import kotlinx.coroutines.flow.toList
import kotlinx.coroutines.runBlocking
import kotlinx.coroutines.withTimeout

class PlanTest : ScratchDir("trailprint-plan-test") {
    private fun storeWithDemo(path: String? = null): Pair<TrailprintStore, Long> {
        val store = if (path == null) TrailprintStore.openInMemory() else TrailprintStore.open(path)
        val b = store.importBuildingJson(TestData.demoBuildingJson, "demo-building.json", false)
        return store to b.id
    }

    private fun request(buildingId: Long, budget: Double, algorithm: PlanAlgorithm = PlanAlgorithm.GREEDY, end: String = "c20", timeLimit: Double? = null) =
        PlanRequest(buildingId, "c00", end, budget, defaultRobotProfile(), algorithm, 7uL, timeLimit)

    /** A plan model of the demo building, imported into [api]: loaded, with [start] and [end] tapped. */
    private suspend fun CoroutineScope.tappedPlanModel(api: Trailprint, start: String, end: String): Pair<Long, PlanModel> {
        val bid = api.importBuilding(TestData.demoBuildingJson, "demo").id
        val model = PlanModel(api, this, bid)
        model.load().join()
        model.tapVertex(start)
        model.tapVertex(end)
        return bid to model
    }

    @Test
    fun plansWithinBudgetReportsProgressAndSavesThePlan() {
        val db = File(dir, "p.db").path
        val (store, bid) = storeWithDemo(db)
        val reports = CopyOnWriteArrayList<PlanProgress>()
        val plan = store.use {
            it.newPlan(request(bid, 60.0, PlanAlgorithm.GENETIC)).use { job ->
                job.run(object : PlanListener {
                    override fun onProgress(progress: PlanProgress) {
                        reports += progress
                    }
                })
            }
        }
        assertEquals("c00", plan.walk.first())
        assertEquals("c20", plan.walk.last())
        assertTrue(plan.lengthM <= 60.0 + 1e-9 && plan.lengthM >= 30.0, "length ${plan.lengthM}")
        assertTrue(plan.utilityNats > 0)
        assertEquals("genetic", plan.algorithm)
        assertTrue(reports.isNotEmpty(), "no progress reported")
        assertTrue(reports.all { it.fraction in 0.0..1.0 })
        // A fresh store object on the same file sees the plan.
        TrailprintStore.open(db).use { again ->
            val listed = again.listPlans(bid)
            assertEquals(listOf(plan.id), listed.map { it.id })
            assertEquals(plan.walk, again.getPlan(plan.id).walk)
            assertEquals(defaultRobotProfile(), listed[0].surveyor)
        }
    }

    @Test
    fun cancelsALongPlanFromAnotherThread() {
        val (store, bid) = storeWithDemo()
        store.use {
            val job = it.newPlan(request(bid, 300.0, PlanAlgorithm.EXACT, end = "c00"))
            val started = CountDownLatch(1)
            thread(name = "canceller") {
                started.await(30, TimeUnit.SECONDS)
                Thread.sleep(200)
                job.cancel()
            }
            val t0 = System.nanoTime()
            var lastProgress: PlanProgress? = null
            // A cancelled plan returns its best walk so far, saved like any other plan.
            val best = job.run(object : PlanListener {
                override fun onProgress(progress: PlanProgress) {
                    lastProgress = progress
                    started.countDown()
                }
            })
            val ms = (System.nanoTime() - t0) / 1_000_000
            assertTrue(job.isCancelled())
            assertTrue(ms < 20_000, "cancel took $ms ms")
            assertEquals("cancelled", best.termination)
            assertEquals("c00", best.walk.first())
            assertEquals("c00", best.walk.last())
            assertTrue(best.lengthM <= 300.0 + 1e-9, "length ${best.lengthM}")
            assertTrue(best.utilityNats > 0.0, "utility ${best.utilityNats}")
            // Progress carried the best walk's figures for the app to show.
            val p = lastProgress
            assertTrue(p != null && p.bestUtilityNats != null && p.bestLengthM != null, "progress $p")
            assertEquals(listOf(best.id), it.listPlans(bid).map { plan -> plan.id }, "the best-so-far plan is saved")
            job.close()
        }
    }

    @Test
    fun aBudgetBelowTheShortestWalkIsUnreachableNamingTheShortest() {
        val (store, bid) = storeWithDemo()
        store.use {
            val e = assertFailsWith<TrailprintException.Unreachable> { it.newPlan(request(bid, 10.0)).run(null) }
            assertTrue("c00" in e.message!! && "c20" in e.message!! && "30.000" in e.message!!, e.message)
        }
    }

    @Test
    fun anUnknownVertexIsAnInvalidRequest() {
        val (store, bid) = storeWithDemo()
        store.use {
            val e = assertFailsWith<TrailprintException.InvalidRequest> { it.newPlan(request(bid, 50.0, end = "nowhere")).run(null) }
            assertTrue("nowhere" in e.message!!, e.message)
        }
    }

    @Test
    fun aPlanCallRunsOnce() {
        val (store, bid) = storeWithDemo()
        store.use {
            val job = it.newPlan(request(bid, 40.0))
            job.run(null)
            assertFailsWith<TrailprintException.InvalidRequest> { job.run(null) }
        }
    }

    @Test
    fun theFacadeFlowEndsWithDoneAndCancellingItCancelsThePlanner() = runBlocking {
        Trailprint.inMemory(Dispatchers.IO).use { api ->
            val bid = api.importBuilding(TestData.demoBuildingJson, "demo").id
            val events = withTimeout(60_000) { api.plan(request(bid, 50.0)).toList() }
            assertIs<PlanEvent.Done>(events.last())
            // Take the first progress event of an endless exact search, then stop collecting.
            val first = withTimeout(60_000) { api.plan(request(bid, 300.0, PlanAlgorithm.EXACT, end = "c00")).first() }
            assertIs<PlanEvent.Progress>(first)
            // The cancelled planner stops promptly and saves its best walk so far.
            val deadline = System.nanoTime() + 20_000_000_000L
            while (api.plans(bid).size < 2 && System.nanoTime() < deadline) Thread.sleep(20)
            assertEquals(2, api.plans(bid).size)
        }
    }

    @Test
    fun thePlanModelConvertsMinutesAndPlans() = runBlocking {
        Trailprint.inMemory(Dispatchers.IO).use { api ->
            val (_, model) = tappedPlanModel(api, "c00", "c20")
            assertNotNull(model.state.value.map)
            model.setProfile(Profile.HUMAN)
            model.setBudget(50.0)
            model.setUnit(BudgetUnit.MINUTES)
            // 50 m at 1.2 m/s is 0.694 minutes.
            assertEquals(50.0 / 60.0 / 1.2, model.state.value.budget, 1e-9)
            model.setAlgorithm(PlanAlgorithm.GREEDY)
            model.plan()
            val done = withTimeout(60_000) { model.state.first { !it.planning && (it.result != null || it.error != null) } }
            assertNull(done.error)
            assertTrue(done.result!!.lengthM <= 50.0 + 1e-6)
            assertEquals(defaultHumanProfile().let { (it as dev.trailprint.ffi.SurveyorProfile.Human).scanIntervalS }, (done.result!!.surveyor as dev.trailprint.ffi.SurveyorProfile.Human).scanIntervalS)
            // Unreachable budget: the error message, no result.
            model.setUnit(BudgetUnit.METRES)
            model.setBudget(5.0)
            model.plan()
            val failed = withTimeout(60_000) { model.state.first { !it.planning && it.error != null } }
            assertTrue("fits the budget" in failed.error!!, failed.error)
        }
    }

    /** A 36 x 36 grid of 2 m corridors (1,296 vertices) with its kernel, as building JSON. */
    private fun bigGridJson(): String {
        val n = 36
        val vertices = (0 until n * n).joinToString(",") { i -> """{"id":"g${i % n}_${i / n}","x":${2 * (i % n)},"y":${2 * (i / n)}}""" }
        val edges = buildList {
            for (y in 0 until n) for (x in 0 until n) {
                if (x + 1 < n) add("""{"a":"g${x}_$y","b":"g${x + 1}_$y"}""")
                if (y + 1 < n) add("""{"a":"g${x}_$y","b":"g${x}_${y + 1}"}""")
            }
        }.joinToString(",")
        return """{"format":"survey-building/1","name":"big grid","vertices":[$vertices],"edges":[$edges],""" +
            """"pilot":[{"x":0,"y":0,"rss":{"a":-50}}],"kernel":{"sf2":60,"ell":10,"sn2":4}}"""
    }

    @Test
    fun theTimeLimitRefusalsLimitIsReadFromItsMessage() {
        val msg = "planning on \"b8\" ... needs about 4.1 s on this device, more than the time limit of 2.0 s: ... " +
            "raise the time limit (--time-limit, PlanRequest.time_limit) to 9 s or more, or plan a budget of about 1320 m"
        assertEquals(9.0, PlanState.suggestedTimeLimit(msg))
        assertNull(PlanState.suggestedTimeLimit("no walk from c00 to c20 fits the budget of 5 m"))
        assertNull(PlanState.suggestedTimeLimit(null))
    }

    /**
     * A robot's 2,200 m on a 1,296-vertex floor is 4,401 samples: one exact evaluation takes
     * seconds, so a 0.1 s limit is refused at once (nothing saved), with the limit that would
     * do; the screen's "plan with this much time" then plans and saves the walk.
     */
    @Test
    fun aLimitTooShortForTheAnswerOffersTheTimeItNeeds() = runBlocking {
        Trailprint.inMemory(Dispatchers.IO).use { api ->
            val bid = api.importBuilding(bigGridJson(), "big grid").id
            val model = PlanModel(api, this, bid)
            model.load().join()
            model.tapVertex("g0_0")
            model.tapVertex("g0_0")
            model.setProfile(Profile.ROBOT)
            model.setBudget(2200.0)
            model.setAlgorithm(PlanAlgorithm.AUTO)
            model.plan(0.1)
            val refused = withTimeout(60_000) { model.state.first { !it.planning && it.error != null } }
            assertTrue("more than the time limit of 0.1 s" in refused.error!!, refused.error)
            val limit = assertNotNull(refused.suggestedTimeLimitS, refused.error)
            assertTrue(limit > 0.1, "$limit")
            assertEquals(0, api.plans(bid).size)
            model.planWithSuggestedTime()
            val done = withTimeout(120_000) { model.state.first { !it.planning && (it.result != null || it.error != null) } }
            assertNull(done.error)
            assertTrue(done.result!!.lengthM > 0.9 * 2200.0, "${done.result!!.lengthM}")
            assertEquals(1, api.plans(bid).size)
        }
    }

    @Test
    fun cancellingThePlanModelKeepsTheBestWalkSoFar() = runBlocking {
        Trailprint.inMemory(Dispatchers.IO).use { api ->
            val (bid, model) = tappedPlanModel(api, "c00", "c00")
            model.setBudget(300.0)
            model.setAlgorithm(PlanAlgorithm.EXACT) // hours without a cancel
            model.plan()
            // Cancel once the planner has reported a best walk.
            withTimeout(60_000) { model.state.first { it.progress?.bestUtilityNats != null } }
            model.cancel()
            val done = withTimeout(30_000) { model.state.first { !it.planning } }
            assertNull(done.error)
            val r = done.result
            assertNotNull(r, "the cancelled plan's best walk is the result")
            assertEquals("cancelled", r.termination)
            assertEquals("c00", r.walk.first())
            assertEquals("c00", r.walk.last())
            assertTrue(r.lengthM <= 300.0 + 1e-9 && r.utilityNats > 0.0, "$r")
            assertEquals(listOf(r.id), api.plans(bid).map { it.id }, "and it is saved")
        }
    }
}
