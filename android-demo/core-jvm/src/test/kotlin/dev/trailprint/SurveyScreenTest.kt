package dev.trailprint

import dev.trailprint.ffi.Position
import dev.trailprint.ffi.SessionStatus
import dev.trailprint.survey.SurveyLive
import dev.trailprint.files.ExportFiles
import dev.trailprint.survey.ActiveSurveyFile
import dev.trailprint.survey.SurveyLifecycle
import dev.trailprint.survey.SurveyMode
import dev.trailprint.testing.FakeSensors
import dev.trailprint.testing.ScratchDir
import dev.trailprint.testing.TestData
import dev.trailprint.testing.greedyPlan
import dev.trailprint.ui.FinishModel
import dev.trailprint.ui.SurveyModel
import dev.trailprint.ui.SurveyUiState
import java.io.File
import kotlin.test.Test
import kotlin.test.assertEquals
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

class SurveyScreenTest : ScratchDir("trailprint-ui-test") {
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
    fun theSurveyModelDrivesTheLifecycleAndTheFinishModelWritesFilesToShare() = runBlocking {
        Trailprint.open(File(dir, "ui.db").path, Dispatchers.IO).use { api ->
            val bid = api.importBuilding(TestData.demoBuildingJson, "demo").id
            val plan = api.store.greedyPlan(bid)
            var now = 1_700_000_000_000L
            val scope = CoroutineScope(SupervisorJob() + Dispatchers.Default)
            val sensors = FakeSensors()
            val lifecycle = SurveyLifecycle(api, ActiveSurveyFile(File(dir, "active.json")), sensors, scope, clock = { now })
            val model = SurveyModel(lifecycle, scope)
            lifecycle.start(plan.id, SurveyMode.HUMAN)
            val started = withTimeout(30_000) { model.state.first { it.sessionId != null && it.nextVertex != null } }
            assertEquals("c01", started.nextVertex)
            assertTrue(started.instruction.isNotBlank())
            repeat(4) { now += 600; sensors.step() }
            withTimeout(30_000) { model.state.first { it.walked.size >= 4 } }
            now += 1000
            model.checkInAt("c02").join()
            val after = withTimeout(30_000) { model.state.first { it.walked.size >= 5 } }
            assertTrue(after.fraction > 0.2, "${after.fraction}")
            assertNotNull(after.awakeMessage)
            model.pause().join()
            assertTrue(withTimeout(30_000) { model.state.first { it.paused } }.paused)
            model.pause().join() // pausing twice is the session's error, shown, not thrown
            assertNotNull(withTimeout(30_000) { model.state.first { it.error != null } }.error)
            model.dismissError()
            model.resume().join()
            model.finish().join()
            val done = withTimeout(30_000) { model.state.first { it.finished != null } }
            assertEquals(SessionStatus.FINISHED, done.finished!!.status)
            model.close()
            // A screen opened later on the same service does not take that end for its own.
            val later = SurveyModel(lifecycle, scope)
            assertEquals(done.sessionId, withTimeout(30_000) { later.state.first { it.map != null } }.sessionId)
            assertNull(later.state.value.finished)
            assertTrue(!later.hasActiveSurvey)
            scope.cancel()

            val exports = ExportFiles(File(dir, "exports"), api)
            val finish = FinishModel(api, exports, this, Dispatchers.IO)
            finish.load(done.sessionId!!).join()
            assertNull(finish.state.value.error)
            assertTrue(finish.state.value.lines().first().startsWith("Walked"), finish.state.value.lines().toString())
            finish.shareCsv().join()
            val csv = finish.state.value.share!!
            assertEquals("text/csv", csv.mimeType)
            assertTrue(csv.file.isFile && csv.file.parentFile == exports.dir, "${csv.file}")
            finish.shared()
            assertNull(finish.state.value.share)
        }
    }
}
