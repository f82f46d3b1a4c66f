package dev.trailprint

import dev.trailprint.ffi.PlanAlgorithm
import dev.trailprint.ffi.SessionStatus
import dev.trailprint.ffi.WifiReading
import dev.trailprint.ffi.defaultHumanProfile
import dev.trailprint.files.ExportFiles
import dev.trailprint.team.CoordinatorModel
import dev.trailprint.team.WalkFiles
import dev.trailprint.team.WalkInboxModel
import dev.trailprint.testing.ScratchDir
import dev.trailprint.testing.TestData
import dev.trailprint.testing.greedyPlan
import dev.trailprint.ui.FinishModel
import java.io.File
import java.nio.file.Files
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith
import kotlin.test.assertNotNull
import kotlin.test.assertNull
import kotlin.test.assertTrue
import kotlinx.coroutines.flow.first
import kotlinx.coroutines.runBlocking
import kotlinx.coroutines.withTimeout

/** Issue 19: surveyors share bundles, a coordinator merges them and hands out team walks. */
class TeamFlowTest : ScratchDir("trailprint-teamflow-test") {
    private val t0 = 1_700_000_000_000L

    /** A surveyor's phone that walked c00 -> c06 with [scans] scans and finished. */
    private suspend fun surveyorPhone(name: String, scans: Int, rssBase: Double): Pair<Trailprint, Long> {
        val api = Trailprint.open(File(dir, "$name.db").path)
        val bid = api.importBuilding(TestData.demoBuildingJson, "demo").id
        val plan = api.store.greedyPlan(bid)
        val s = api.startSession(plan.id, defaultHumanProfile())
        var t = t0
        s.checkIn(t, "c00")
        repeat(scans) { i ->
            repeat(2) { t += 600; s.step(t, 1u) }
            s.scan(t + 1, listOf(WifiReading("aa:aa", rssBase - i), WifiReading("bb:bb", rssBase - 20 + i)))
        }
        s.finish(t + 1000)
        val sid = s.id()
        s.close()
        return api to sid
    }

    @Test
    fun surveyorsShareBundlesTheCoordinatorMergesThemAndHandsOutTeamWalks() = runBlocking {
        // Two surveyors finish and share their bundles as files, from the finish screen.
        val bundles = listOf("ann" to -50.0, "bob" to -55.0).map { (name, rss) ->
            val (phone, sid) = surveyorPhone(name, scans = if (name == "ann") 3 else 2, rssBase = rss)
            val finish = FinishModel(phone, ExportFiles(File(dir, "$name-exports"), phone), this)
            finish.load(sid).join()
            finish.shareBundle(device = "$name-phone", surveyorName = name.replaceFirstChar { it.uppercase() }).join()
            val f = finish.state.value.share
            assertNotNull(f, finish.state.value.error)
            assertEquals("application/json", f.mimeType)
            assertTrue(f.file.name.endsWith(".json") && name in f.file.name, f.file.name)
            phone.close()
            f.file
        }

        // The coordinator imports both, and a damaged third file that must change nothing.
        val desk = Trailprint.open(File(dir, "coordinator.db").path)
        val exports = ExportFiles(File(dir, "coordinator-exports"), desk)
        val coord = CoordinatorModel(desk, exports, this, device = "desk-phone", coordinatorName = "Cleo", clock = { t0 + 3_600_000 })
        val damaged = bundles[1].readText().let { it.substring(0, it.length / 2) }
        coord.importBundles(bundles.map { it.name to it.readText() } + ("broken.json" to damaged)).join()
        val s = coord.state.value
        assertNull(s.error)
        assertEquals(3, s.receipts.size)
        val (ann, bob, broken) = s.receipts
        assertTrue(ann.summary!!.buildingCreated)
        assertEquals(1uL, ann.summary!!.sessionsAdded)
        assertEquals(3L, ann.fingerprintsAdded)
        assertEquals("Ann", ann.surveyorName)
        assertEquals("ann-phone", ann.device)
        assertEquals(2L, bob.fingerprintsAdded)
        assertTrue(ann.line().contains("Ann on ann-phone") && ann.line().contains("3 fingerprints"), ann.line())
        assertNotNull(broken.error)
        assertTrue("broken.json" in broken.line() && "not imported" in broken.line(), broken.line())
        val building = s.building!!
        assertEquals(5uL, building.collected)
        assertEquals(2, desk.sessions(building.id).size)
        // Importing Ann's again adds nothing, and says so.
        coord.importBundles(listOf(bundles[0].name to bundles[0].readText())).join()
        val againReceipt = coord.state.value.receipts.last()
        assertEquals(0uL, againReceipt.summary!!.sessionsAdded)
        assertEquals(0L, againReceipt.fingerprintsAdded)

        // Plan the next walks for two surveyors as a team; one walk file each.
        coord.setTeam(2, "c10", "c10", 30.0)
        coord.setAlgorithm(PlanAlgorithm.GREEDY)
        coord.plan().join()
        assertNull(coord.state.value.error)
        val team = coord.state.value.team!!
        assertEquals(2, team.files.size)
        assertEquals(team.summary.walks, team.assignments.map { it.walk })
        assertTrue(team.files.all { it.file.isFile && it.mimeType == "application/json" })
        assertEquals(listOf(1, 2), team.assignments.map { it.member })

        // Surveyor 2's phone (a fresh one: it has never seen the building) opens its walk.
        val carol = Trailprint.open(File(dir, "carol.db").path)
        val inbox = WalkInboxModel(carol, this)
        val file2 = team.files[1].file
        inbox.open(file2.name, file2.readText()).join()
        val got = inbox.state.value.received
        assertNotNull(got, inbox.state.value.error)
        assertEquals(team.summary.walks[1], got.plan.walk)
        assertEquals(2, got.assignment.member)
        assertEquals(2, got.assignment.members)
        assertTrue(inbox.state.value.lines().first().startsWith("Walk 2 of 2"), inbox.state.value.lines().toString())
        // The walk is a plan to start a survey on, and the team's data came with it.
        assertEquals(5uL, carol.buildings().single().collected)
        val session = carol.startSession(got.plan.id, got.plan.surveyor ?: defaultHumanProfile())
        assertEquals(team.summary.walks[1].getOrNull(1), session.guidance().nextVertex)
        assertEquals(SessionStatus.ACTIVE, session.status())
        session.close()
        // Opening the same file again is harmless and finds the same walk.
        inbox.open(file2.name, file2.readText()).join()
        assertEquals(team.summary.walks[1], inbox.state.value.received!!.plan.walk)
        carol.close()
        desk.close()
    }

    @Test
    fun theCoordinatorSeesTheTeamPlansProgressAndStopKeepsTheWalksSoFar() = runBlocking {
        val desk = Trailprint.open(File(dir, "stop.db").path)
        val bid = desk.importBuilding(TestData.demoBuildingJson, "demo").id
        val coord = CoordinatorModel(desk, ExportFiles(File(dir, "stop-exports"), desk), this)
        coord.selectBuilding(bid).join()
        coord.setTeam(2, "c00", "c00", 300.0)
        coord.setAlgorithm(PlanAlgorithm.EXACT) // branch and bound on 300 m: hours without the stop
        val planning = coord.plan()
        val line = withTimeout(60_000) {
            coord.state.first { it.planProgress?.contains("team best") == true }.planProgress!!
        }
        assertTrue(line.startsWith("surveyor 1/2, in turn: "), line)
        coord.stopPlanning()
        withTimeout(30_000) { planning.join() }
        val s = coord.state.value
        assertNull(s.error)
        assertNull(s.planProgress)
        val team = s.team!!
        assertTrue(team.summary.cancelled)
        assertEquals(2, team.files.size)
        assertTrue(team.assignments.all { it.walk.first() == "c00" && it.walk.last() == "c00" && it.lengthM <= 300.0 + 1e-9 })
        desk.close()
    }

    @Test
    fun aDamagedWalkFileIsRefusedNamingTheFieldAndChangesNothing() = runBlocking {
        val (phone, _) = surveyorPhone("dan", scans = 1, rssBase = -60.0)
        val bid = phone.buildings().single().id
        val bundle = phone.exportBundle(bid, "dan-phone", "Dan")
        phone.close()
        val good = dev.trailprint.team.WalkAssignment("t", 1, 1, "Eve", "demo office", "c00", "c06", 9.0, listOf("c00", "c06"), 9.0, 1.0)
        val fresh = Trailprint.open(File(dir, "fresh.db").path)
        val bad = WalkFiles.encode(good.copy(member = 3, members = 2), bundle)
        val e = assertFailsWith<AppException> { WalkFiles.open(fresh, bad, "walk.json") }
        assertTrue("walk.json" in e.message!! && "assignment.member" in e.message!!, e.message)
        val notAWalk = assertFailsWith<AppException> { WalkFiles.open(fresh, "{\"format\":\"trailprint-bundle/1\"}", "other.json") }
        assertTrue("field format" in notAWalk.message!!, notAWalk.message)
        val truncated = assertFailsWith<AppException> { WalkFiles.open(fresh, WalkFiles.encode(good, bundle).take(300), "cut.json") }
        assertTrue("cut.json" in truncated.message!!, truncated.message)
        assertTrue(fresh.buildings().isEmpty(), "nothing was imported")
        fresh.close()
    }
}
