package dev.trailprint.testing

import dev.trailprint.ffi.PlanAlgorithm
import dev.trailprint.ffi.PlanRequest
import dev.trailprint.ffi.PlanSummary
import dev.trailprint.ffi.SurveyorProfile
import dev.trailprint.ffi.TrailprintStore
import dev.trailprint.ffi.defaultHumanProfile
import java.io.File

/** Files the tests share; the repository root comes from `-Dtrailprint.repo`. */
object TestData {
    val repo: File = File(System.getProperty("trailprint.repo") ?: ".").absoluteFile

    val demoBuildingFile: File = File(repo, "android-demo/demo/demo-building.json")

    val demoBuildingJson: String by lazy { demoBuildingFile.readText() }
}

/**
 * The tests' usual plan of the demo building [buildingId]: greedy (seed 1) from c00 to
 * [end] within [budget] metres, for [profile], run to its end and saved.
 */
fun TrailprintStore.greedyPlan(
    buildingId: Long,
    end: String = "c06",
    budget: Double = 9.0,
    profile: SurveyorProfile = defaultHumanProfile(),
): PlanSummary = newPlan(PlanRequest(buildingId, "c00", end, budget, profile, PlanAlgorithm.GREEDY, 1uL, null)).use { it.run(null) }
