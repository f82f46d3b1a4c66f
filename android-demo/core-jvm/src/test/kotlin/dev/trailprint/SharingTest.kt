package dev.trailprint

import dev.trailprint.ffi.PlanAlgorithm
import dev.trailprint.ffi.TrailprintException
import dev.trailprint.ffi.WifiReading
import dev.trailprint.ffi.defaultHumanProfile
import dev.trailprint.files.Destination
import dev.trailprint.files.ExportFiles
import dev.trailprint.files.Incoming
import dev.trailprint.files.IncomingRouter
import dev.trailprint.files.takeEachBatch
import dev.trailprint.json.Json
import dev.trailprint.json.path
import dev.trailprint.team.CoordinatorModel
import dev.trailprint.team.WalkInbox
import dev.trailprint.team.WalkInboxModel
import dev.trailprint.testing.ScratchDir
import dev.trailprint.testing.TestData
import dev.trailprint.testing.greedyPlan
import dev.trailprint.ui.PastSurveysModel
import java.io.ByteArrayInputStream
import java.io.File
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith
import kotlin.test.assertNotNull
import kotlin.test.assertNull
import kotlin.test.assertTrue
import kotlinx.coroutines.channels.Channel
import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.launch
import kotlinx.coroutines.runBlocking
import kotlinx.coroutines.withTimeout

/**
 * Issue 19: files that arrive on a phone (routed by what they are), walk files kept until
 * the surveyor opens them, and past surveys shared again, one or several at a time.
 */
class SharingTest : ScratchDir("trailprint-sharing-test") {
    private val t0 = 1_700_000_000_000L

    /** Walks c00 -> c06 on [api]'s building [bid] with [scans] scans; finished unless [finish] is false. */
    private fun survey(api: Trailprint, bid: Long, scans: Int, startMs: Long, finish: Boolean = true): Long {
        val plan = api.store.greedyPlan(bid)
        return api.store.startSession(plan.id, defaultHumanProfile(), null).use { s ->
            var t = startMs
            s.checkIn(t, "c00")
            repeat(scans) { i ->
                repeat(2) { t += 600; s.step(t, 1u) }
                s.scan(t + 1, listOf(WifiReading("aa:aa", -50.0 - i), WifiReading("bb:bb", -70.0 + i)))
            }
            if (finish) s.finish(t + 1000) else s.abort(t + 1000, "carrier")
            s.id()
        }
    }

    /** A real walk file: a surveyor's bundle, imported by a coordinator who plans one walk. */
    private suspend fun walkFile(): File {
        val phone = Trailprint.open(File(dir, "ann.db").path)
        val bid = phone.importBuilding(TestData.demoBuildingJson, "demo").id
        survey(phone, bid, scans = 2, startMs = t0)
        val bundle = phone.exportBundle(bid, "ann-phone", "Ann")
        phone.close()
        val desk = Trailprint.open(File(dir, "desk.db").path)
        kotlinx.coroutines.coroutineScope {
            val coord = CoordinatorModel(desk, ExportFiles(File(dir, "desk-exports"), desk), this, clock = { t0 + 3_600_000 })
            coord.importBundles(listOf("ann.json" to bundle)).join()
            coord.setTeam(1, "c10", "c10", 30.0)
            coord.setAlgorithm(PlanAlgorithm.GREEDY)
            coord.plan().join()
            assertNull(coord.state.value.error)
        }
        desk.close()
        return File(dir, "desk-exports").listFiles()!!.single { "-walk-" in it.name }
    }

    @Test
    fun anIncomingFileIsRoutedByWhatItIsAndAnythingElseIsRefusedByName() = runBlocking {
        val walk = walkFile()
        val bundleText = Trailprint.open(File(dir, "ann.db").path).use { it.exportBundle(it.buildings().single().id) }
        fun classify(name: String, text: String, type: String? = "application/json") = IncomingRouter.classify(name, type, text.toByteArray())

        assertTrue(classify(walk.name, walk.readText()) is Incoming.Walk)
        // A bundle's own "format" comes after its body (sorted keys), and the building inside
        // the body has one too ("survey-building/1"): the top-level one decides.
        assertTrue(bundleText.indexOf("\"survey-building/1\"") in 0 until bundleText.indexOf("\"trailprint-bundle/1\""))
        assertTrue(classify("ann.json", bundleText, "application/octet-stream") is Incoming.Bundle)
        assertTrue(classify("office.json", TestData.demoBuildingJson, null) is Incoming.Building)
        // A format only inside the body is not the file's.
        val nested = classify("n.json", """{"body":{"format":"trailprint-walk/1"},"x":"\"format\":\"trailprint-walk/1\""}""")
        assertTrue(nested is Incoming.Refused && "without a top-level \"format\"" in nested.reason, "$nested")

        val refused = listOf(
            IncomingRouter.classify("photo.png", "image/png", byteArrayOf(0x89.toByte(), 0x50, 0x4e, 0x47)),
            IncomingRouter.classify("blob.bin", "application/octet-stream", byteArrayOf(0xff.toByte(), 0xfe.toByte(), 0x00, 0x41)),
            classify("empty.json", ""),
            classify("list.json", "[1, 2]"),
            classify("new.json", """{"format":"trailprint-bundle/9","body":{}}"""),
        ).map { it as Incoming.Refused }
        assertTrue("image/png" in refused[0].reason, refused[0].reason)
        assertTrue("not UTF-8" in refused[1].reason, refused[1].reason)
        assertTrue("empty" in refused[2].reason, refused[2].reason)
        assertTrue("starts with '['" in refused[3].reason, refused[3].reason)
        assertTrue("trailprint-bundle/9" in refused[4].reason && "older" in refused[4].reason, refused[4].reason)
        assertTrue(refused.all { it.line().startsWith(it.name + ": ") })

        // Where the app goes.
        val w = classify(walk.name, walk.readText())
        val b = classify("ann.json", bundleText)
        assertEquals(Destination.WALK, IncomingRouter.route(listOf(w)).destination)
        assertEquals(Destination.TEAM, IncomingRouter.route(listOf(w, b, refused[0])).destination)
        assertEquals(Destination.BUILDINGS, IncomingRouter.route(listOf(classify("o.json", TestData.demoBuildingJson))).destination)
        val onlyBad = IncomingRouter.route(refused)
        assertEquals(Destination.STAY, onlyBad.destination)
        assertEquals(refused.size, onlyBad.message!!.lines().size)
        assertTrue(onlyBad.message!!.lines().all { it.startsWith("Not opened — ") })
        // During a survey the app stays on it, and says where the files wait.
        val during = IncomingRouter.route(listOf(w, b), surveyRunning = true)
        assertEquals(Destination.STAY, during.destination)
        assertTrue("2 received files" in during.message!! && "Not opened" in during.message!!, during.message)
        assertEquals(1, during.walks.size)
        assertEquals(1, during.bundles.size)

        // Sizes: read up to the limit, refuse past it without reading it all.
        assertEquals(5, IncomingRouter.readLimited(ByteArrayInputStream(ByteArray(5)), limit = 5)!!.size)
        assertNull(IncomingRouter.readLimited(ByteArrayInputStream(ByteArray(6)), limit = 5))
        assertTrue("256 MiB" in IncomingRouter.tooLarge("huge.json").reason)
    }

    @Test
    fun filesWaitingForTheirScreenAreTakenOnceABatch() = runBlocking {
        val waiting = MutableStateFlow<List<Incoming.Bundle>>(emptyList())
        val taken = Channel<List<String>>(Channel.UNLIMITED)
        val screen = launch { waiting.takeEachBatch { files -> taken.send(files.map { it.name }) } }
        waiting.value = listOf(Incoming.Bundle("a.json", "{}"), Incoming.Bundle("b.json", "{}"))
        assertEquals(listOf("a.json", "b.json"), withTimeout(5_000) { taken.receive() })
        assertTrue(waiting.value.isEmpty(), "a batch taken leaves the flow")
        waiting.value = listOf(Incoming.Bundle("c.json", "{}"))
        assertEquals(listOf("c.json"), withTimeout(5_000) { taken.receive() })
        screen.cancel()
        assertTrue(taken.tryReceive().isFailure, "each batch is taken once")
    }

    @Test
    fun aWalkFileReceivedDuringASurveyWaitsNotOpenedAndOpensLaterAsAPlan() = runBlocking {
        val walk = walkFile()
        val phone = Trailprint.open(File(dir, "carol.db").path)
        val box = File(dir, "carol-inbox")
        var clock = t0
        // Received while a survey runs: kept, not asked about, not imported.
        val during = WalkInboxModel(phone, this, WalkInbox(box) { clock })
        during.receive(listOf(walk.name to walk.readText(), "bad.json" to """{"format":"trailprint-walk/1"}"""), ask = false).join()
        val s1 = during.state.value
        assertNull(s1.pending)
        assertEquals(1, s1.inbox.size)
        assertTrue(s1.inbox.single().line().endsWith("Not opened"), s1.inbox.single().line())
        assertTrue(s1.error != null && "bad.json" in s1.error!! && "assignment" in s1.error!!, s1.error)
        assertTrue(phone.buildings().isEmpty(), "nothing imported behind the surveyor's back")

        // The app restarts; the walk is still there, "Not opened"; the surveyor taps it.
        clock += 60_000
        val later = WalkInboxModel(phone, this, WalkInbox(box) { clock })
        later.refresh().join()
        val entry = later.state.value.inbox.single()
        assertNull(entry.openedPlanId)
        later.ask(entry)
        val q = later.state.value.pendingQuestion()!!
        assertTrue(q.startsWith(walk.name) && "walk 1 of 1" in q && "Open it as the plan to walk?" in q, q)
        later.later()
        assertNull(later.state.value.pending)
        assertEquals(1, WalkInbox(box).notOpened().size)

        // Open it: the walk is a saved plan, and the entry says which.
        later.ask(entry)
        later.openPending().join()
        val got = later.state.value.received
        assertNotNull(got, later.state.value.error)
        assertEquals(entry.assignment.walk, got.plan.walk)
        assertEquals(got.plan.id, WalkInbox(box).entries().single().openedPlanId)
        assertTrue(later.state.value.inbox.single().line().endsWith("Opened (plan ${got.plan.id})"))
        assertTrue(WalkInbox(box).notOpened().isEmpty())
        // The same file shared again keeps its status, and is not asked about again.
        later.receive(listOf(walk.name to walk.readText())).join()
        assertNull(later.state.value.pending)
        assertEquals(1, later.state.value.inbox.size)
        phone.close()
    }

    @Test
    fun pastSurveysAreSharedAgainOneOrSeveralAtATimeAsFiles() = runBlocking {
        val api = Trailprint.open(File(dir, "phone.db").path)
        val office = api.importBuilding(TestData.demoBuildingJson, "demo").id
        val annex = api.importBuilding(TestData.demoBuildingJson.replaceFirst("\"Demo office\"", "\"Annex\""), "annex").id
        val a1 = survey(api, office, scans = 2, startMs = t0)
        val carrier = survey(api, office, scans = 0, startMs = t0 + 1000, finish = false)
        val a2 = survey(api, office, scans = 3, startMs = t0 + 2000)
        val b1 = survey(api, annex, scans = 1, startMs = t0 + 3000)
        val exports = ExportFiles(File(dir, "phone-exports"), api)
        val past = PastSurveysModel(api, exports, this)
        past.refresh().join()
        val list = past.state.value.surveys
        // Sessions with data only (the empty carrier is not a survey), newest first.
        assertEquals(setOf(a1, a2, b1), list.map { it.sessionId }.toSet())
        assertTrue(carrier !in list.map { it.sessionId })
        assertEquals(list.sortedByDescending { it.createdMs }, list)
        assertEquals(3L, list.single { it.sessionId == a2 }.fingerprints)
        assertTrue(list.single { it.sessionId == b1 }.line().startsWith("Annex · session $b1"))

        // One survey's CSV, again.
        past.shareCsv(a1).join()
        val csv = past.state.value.share.single()
        assertEquals("text/csv", csv.mimeType)
        assertEquals(api.resumeSession(a1).use { it.exportCsv() }, csv.file.readText())
        past.shared()

        // Three ticked surveys of two buildings: two bundle files, each of exactly its sessions.
        listOf(a1, a2, b1).forEach(past::toggle)
        past.shareSelectedBundles("my-phone", "Ann").join()
        assertNull(past.state.value.error)
        val files = past.state.value.share
        assertEquals(2, files.size)
        val desk = Trailprint.open(File(dir, "desk2.db").path)
        val imported = files.map { desk.importBundle(it.file.readText(), it.file.name) }.associateBy { it.building }
        assertEquals(2uL, imported.getValue("Demo office").sessionsAdded)
        assertEquals(1uL, imported.getValue("Annex").sessionsAdded)
        assertEquals(5uL, desk.buildings().single { it.name == "Demo office" }.collected)
        val body = Json.parse(files.single { "demo-office" in it.file.name }.file.readText())
        assertEquals("Ann", body.path("body", "surveyor_name"))
        desk.close()

        // Nothing ticked: a message, no file.
        listOf(a1, a2, b1).forEach(past::toggle)
        past.shared()
        past.shareSelectedBundles(null, null).join()
        assertTrue("tick" in past.state.value.error!!)
        assertTrue(past.state.value.share.isEmpty())

        // The binding refuses what a bundle cannot hold, naming it.
        val mixed = assertFailsWith<TrailprintException.InvalidRequest> { api.exportSessionsBundle(listOf(a1, b1)) }
        assertTrue("session $b1" in mixed.message!! && "Annex" in mixed.message!!, mixed.message)
        val unknown = assertFailsWith<TrailprintException.NotFound> { api.exportSessionsBundle(listOf(a1, 999_999)) }
        assertTrue("session 999999" in unknown.message!!, unknown.message)
        assertFailsWith<TrailprintException.InvalidRequest> { api.exportSessionsBundle(emptyList()) }
        api.close()
    }
}
