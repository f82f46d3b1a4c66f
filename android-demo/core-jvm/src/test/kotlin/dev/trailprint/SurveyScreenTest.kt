package dev.trailprint

import dev.trailprint.ffi.PlanAlgorithm
import dev.trailprint.ffi.PlanRequest
import dev.trailprint.ffi.Position
import dev.trailprint.ffi.SessionStatus
import dev.trailprint.ffi.defaultHumanProfile
import dev.trailprint.survey.SurveyLive
import dev.trailprint.testing.TestData
import dev.trailprint.ui.FinishModel
import dev.trailprint.ui.SurveyModel
import dev.trailprint.ui.SurveyUiState
import java.io.File
import java.nio.file.Files
import kotlin.test.AfterTest
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertNotNull
import kotlin.test.assertNull
import kotlin.test.assertTrue
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.cancelAndJoin
import kotlinx.coroutines.flow.first
import kotlinx.coroutines.runBlocking
import kotlinx.coroutines.withTimeout

class SurveyScreenTest {
    private val dir: File = Files.createTempDirectory("trailprint-ui-test").toFile()

    @AfterTest
    fun cleanUp() {
        dir.deleteRecursively()
    }

    @Test
    fun theScreenStateDrawsTheWalkAheadFromTheEstimate() = runBlocking {
        Trailprint.inMemory().use { api ->
            val map = api.map(api.importBuilding(TestData.demoBuildingJson, "demo").id)
            val live = SurveyLive(track = listOf(Position(0.0, 0.0, 0), Position(1.4, 0.0, 0)))
            val s = SurveyUiState.of(map, null, 7, live, listOf("c01", "c02"))
            assertEquals(7L, s.sessionId)
            assertEquals(1.4, s.estimate!!.x)
            // From the estimate to c01 (1.5, 0) and c02 (3, 0).
            assertEquals(listOf(1.4, 1.5, 3.0), s.planned.map { it.x })
            assertEquals(2, s.walked.size)
            assertNull(s.next)
            assertEquals(false, s.checkInDue)
        }
    }

    @Test
    fun theSurveyModelStartsAChecksInAndFinishesAndTheFinishModelExports() = runBlocking {
        Trailprint.open(File(dir, "ui.db").path, Dispatchers.IO).use { api ->
            val bid = api.importBuilding(TestData.demoBuildingJson, "demo").id
            val plan = api.store.newPlan(PlanRequest(bid, "c00", "c06", 9.0, defaultHumanProfile(), PlanAlgorithm.GREEDY, 1uL, null)).use { it.run(null) }
            var now = 1_700_000_000_000L
            val model = SurveyModel(api, this, Dispatchers.IO, clock = { now })
            val job = model.start(plan.id, defaultHumanProfile())
            val started = withTimeout(30_000) { model.state.first { it.sessionId != null && it.nextVertex != null } }
            assertEquals("c01", started.nextVertex)
            assertTrue(started.instruction.isNotBlank())
            val c = model.controller!!
            repeat(4) { now += 600; c.step() }
            now += 1000
            model.checkInAt("c02").join()
            val after = withTimeout(30_000) { model.state.first { it.walked.size >= 5 } }
            assertTrue(after.fraction > 0.2, "${after.fraction}")
            model.finish().join()
            val done = withTimeout(30_000) { model.state.first { it.finished != null } }
            assertEquals(SessionStatus.FINISHED, done.finished!!.status)
            job.cancelAndJoin()
            val finish = FinishModel(api, this, Dispatchers.IO)
            finish.load(done.sessionId!!).join()
            val f = finish.state.value
            assertNull(f.error)
            assertNotNull(f.exportCsv)
            assertTrue(f.lines().first().startsWith("Walked"), f.lines().toString())
        }
    }
}
