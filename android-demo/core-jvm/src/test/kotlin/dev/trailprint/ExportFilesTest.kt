package dev.trailprint

import dev.trailprint.ffi.WifiReading
import dev.trailprint.ffi.defaultHumanProfile
import dev.trailprint.files.ExportFiles
import dev.trailprint.files.writeFileAtomically
import dev.trailprint.testing.ScratchDir
import dev.trailprint.testing.TestData
import dev.trailprint.testing.greedyPlan
import java.io.File
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith
import kotlin.test.assertTrue
import kotlinx.coroutines.runBlocking

/** Issue 19: exports leave the phone as files, written so that a crash loses nothing. */
class ExportFilesTest : ScratchDir("trailprint-export-test") {
    @Test
    fun aLongSurveysExportsAreFilesWithTheSessionsData() = runBlocking {
        Trailprint.open(File(dir, "e.db").path).use { api ->
            val bid = api.importBuilding(TestData.demoBuildingJson, "demo").id
            val plan = api.store.greedyPlan(bid)
            val s = api.startSession(plan.id, defaultHumanProfile())
            var t = 1_700_000_000_000L
            s.checkIn(t, "c00")
            // Many scans with many access points (a long survey's export is megabytes: far past
            // what an intent carries; this one is kept small enough for a quick test).
            val aps = (0 until 80).map { "02:00:00:00:%02x:%02x".format(it / 256, it % 256) }
            repeat(120) { i ->
                t += 2000
                s.scan(t, aps.mapIndexed { k, b -> WifiReading(b, -40.0 - (i + k) % 50) })
            }
            s.finish(t + 1000)
            val sid = s.id()
            val csvText = s.exportCsv()
            val jsonText = s.exportJson()
            s.close()
            val exports = ExportFiles(File(dir, "exports"), api)
            val csv = exports.sessionCsv(sid)
            val json = exports.sessionJson(sid)
            val bundle = exports.bundle(bid, "pixel", "Ann Lee")
            assertEquals(csvText, csv.file.readText())
            assertEquals(jsonText, json.file.readText())
            assertEquals(121, csv.file.readLines().count { it.isNotBlank() }, "a header and one row per scan")
            assertEquals("trailprint-demo-office-session-$sid.csv", csv.file.name)
            assertEquals("trailprint-demo-office-session-$sid.json", json.file.name)
            assertEquals("trailprint-demo-office-bundle-ann-lee.json", bundle.file.name)
            assertEquals(listOf("text/csv", "application/json", "application/json"), listOf(csv, json, bundle).map { it.mimeType })
            // The bundle file is what a coordinator imports.
            Trailprint.inMemory().use { desk -> assertEquals(1uL, desk.importBundle(bundle.file.readText(), bundle.file.name).sessionsAdded) }
            // Only the three files: no temporary file is left behind.
            assertEquals(3, exports.dir.listFiles()!!.size, exports.dir.listFiles()!!.joinToString())
        }
    }

    @Test
    fun aFailedWriteKeepsTheOldFileAndNamesIt() {
        val f = File(dir, "out.csv")
        writeFileAtomically(f, "old\n")
        writeFileAtomically(f, "new\n")
        assertEquals("new\n", f.readText())
        // The target is a non-empty directory: the rename fails, the error names the file.
        val blocked = File(dir, "blocked.csv").also { it.mkdirs(); File(it, "x").writeText("x") }
        val e = assertFailsWith<AppException> { writeFileAtomically(blocked, "text") }
        assertTrue("blocked.csv" in e.message!!, e.message)
        assertTrue(dir.listFiles()!!.none { it.name.endsWith(".part") }, dir.listFiles()!!.joinToString())
        assertEquals("new\n", f.readText())
    }
}
