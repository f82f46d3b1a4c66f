package dev.trailprint

import dev.trailprint.ffi.TrailprintException
import dev.trailprint.ffi.TrailprintStore
import dev.trailprint.testing.ScratchDir
import dev.trailprint.testing.TestData
import dev.trailprint.ui.BuildingsModel
import java.io.File
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith
import kotlin.test.assertNotNull
import kotlin.test.assertNull
import kotlin.test.assertTrue
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.runBlocking
import kotlinx.coroutines.withTimeout
import kotlinx.coroutines.flow.first

class StoreTest : ScratchDir("trailprint-store-test") {
    @Test
    fun importsListsAndDrawsABuildingThatSurvivesReopening() {
        val db = File(dir, "t.db").path
        TrailprintStore.open(db).use { store ->
            val b = store.importBuildingJson(TestData.demoBuildingJson, "demo-building.json", false)
            assertEquals("Demo office", b.name)
            assertEquals(48uL, b.vertices)
            assertEquals(10uL, b.pilot)
            assertTrue(b.hasKernel)
            assertEquals("demo-building.json", b.source)
        }
        TrailprintStore.open(db).use { store ->
            val list = store.listBuildings()
            assertEquals(listOf("Demo office"), list.map { it.name })
            val map = store.buildingMap(list[0].id)
            assertEquals(60, map.edges.size)
            assertEquals(6.0, store.kernel(list[0].id)!!.ell)
        }
    }

    @Test
    fun importsAFileByPath() {
        TrailprintStore.openInMemory().use { store ->
            val b = store.importBuildingFile(TestData.demoBuildingFile.path, false)
            assertEquals(TestData.demoBuildingFile.path, b.source)
        }
    }

    @Test
    fun fitsAndRecordsTheKernel() {
        TrailprintStore.openInMemory().use { store ->
            val noKernel = TestData.demoBuildingJson.substringBefore(",\n \"kernel\"") + "\n}\n"
            val b = store.importBuildingJson(noKernel, "no-kernel.json", false)
            assertNull(store.kernel(b.id))
            val fit = store.fit(b.id)
            assertEquals(fit.kernel, store.kernel(b.id))
            assertEquals(1uL, store.listBuildings().single().fits)
        }
    }

    @Test
    fun theSameNameTwiceIsAlreadyExistsUnlessReplaced() {
        TrailprintStore.openInMemory().use { store ->
            store.importBuildingJson(TestData.demoBuildingJson, "a.json", false)
            val e = assertFailsWith<TrailprintException.AlreadyExists> {
                store.importBuildingJson(TestData.demoBuildingJson, "b.json", false)
            }
            assertTrue("Demo office" in e.message!!, e.message)
            val again = store.importBuildingJson(TestData.demoBuildingJson, "b.json", true)
            assertEquals("b.json", again.source)
            assertEquals(1, store.listBuildings().size)
        }
    }

    @Test
    fun anUnknownBuildingIsNotFound() {
        TrailprintStore.openInMemory().use { store ->
            val e = assertFailsWith<TrailprintException.NotFound> { store.buildingMap(4242) }
            assertTrue("4242" in e.message!!, e.message)
        }
    }

    @Test
    fun aFileThatIsNotADatabaseIsADatabaseErrorNamingThePath() {
        val junk = File(dir, "junk.db").apply { writeText("this is not SQLite, just text that is long enough ".repeat(50)) }
        val e = assertFailsWith<TrailprintException.Database> { TrailprintStore.open(junk.path) }
        assertTrue(junk.path in e.message!!, e.message)
    }

    @Test
    fun aMissingImportFileIsAnIoErrorNamingThePath() {
        TrailprintStore.openInMemory().use { store ->
            val missing = File(dir, "missing.json").path
            val e = assertFailsWith<TrailprintException.Io> { store.importBuildingFile(missing, false) }
            assertTrue(missing in e.message!!, e.message)
        }
    }

    @Test
    fun theBuildingsModelImportsAndShowsErrors() = runBlocking {
        Trailprint.inMemory(Dispatchers.IO).use { api ->
            val model = BuildingsModel(api, this)
            model.import(TestData.demoBuildingJson, "demo-building.json").join()
            assertEquals(listOf("Demo office"), model.state.value.buildings.map { it.name })
            model.import("{\"format\": \"survey-building/9\"}", "bad.json").join()
            val s = model.state.value
            assertNotNull(s.error)
            assertTrue("bad.json" in s.error!!, s.error)
            assertEquals(1, s.buildings.size)
            model.dismissError()
            assertNull(withTimeout(1000) { model.state.first { !it.busy } }.error)
        }
    }
}
