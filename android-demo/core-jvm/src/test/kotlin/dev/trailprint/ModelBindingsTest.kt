package dev.trailprint

import dev.trailprint.ffi.SurveyorProfile
import dev.trailprint.ffi.TrailprintException
import dev.trailprint.ffi.defaultHumanProfile
import dev.trailprint.ffi.defaultRobotProfile
import dev.trailprint.ffi.fitBuildingKernel
import dev.trailprint.ffi.walkUtility
import dev.trailprint.testing.TestData
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith
import kotlin.test.assertFalse
import kotlin.test.assertTrue

class ModelBindingsTest {
    private val json get() = TestData.demoBuildingJson

    @Test
    fun defaultProfilesAreTheSpecDefaults() {
        assertEquals(SurveyorProfile.Human(0.7, 1.2, 4.0, 0.05, 30.0), defaultHumanProfile())
        assertEquals(SurveyorProfile.Robot(0.5, 0.5), defaultRobotProfile())
    }

    @Test
    fun fitsTheKernelOnPilotDataWithinTheSpecBounds() {
        val fit = fitBuildingKernel(json, "demo")
        assertTrue(fit.kernel.sn2 >= 1.0 && fit.kernel.ell in 0.5..1000.0, "${fit.kernel}")
        assertEquals(10u, fit.locations)
        assertTrue(fit.apsUsed.isNotEmpty())
        // The demo building's access points are heard at half its pilot locations: SPEC 2's rule.
        assertFalse(fit.heardOnly)
    }

    @Test
    fun longerWalksCollectMoreInformation() {
        val short = walkUtility(json, "demo", listOf("c00", "c01", "c02"), defaultRobotProfile(), null)
        val long = walkUtility(json, "demo", (0..10).map { "c%02d".format(it) }, defaultRobotProfile(), null)
        assertTrue(short > 0 && long > short, "short $short, long $long")
        // The human model adds label noise: never more information than the robot.
        val human = walkUtility(json, "demo", (0..10).map { "c%02d".format(it) }, defaultHumanProfile(), null)
        assertTrue(human <= long, "human $human vs robot $long")
    }

    @Test
    fun aWalkThatSkipsAnEdgeIsAnInvalidRequestNamingTheVertices() {
        val e = assertFailsWith<TrailprintException.InvalidRequest> {
            walkUtility(json, "demo", listOf("c00", "c05"), defaultRobotProfile(), null)
        }
        assertTrue("c00" in e.message!! && "c05" in e.message!!, e.message)
    }

    @Test
    fun aBadSurveyorModelIsAnInvalidRequestNamingTheParameter() {
        val e = assertFailsWith<TrailprintException.InvalidRequest> {
            walkUtility(json, "demo", listOf("c00", "c01"), SurveyorProfile.Human(0.7, -1.0, 4.0, 0.05, 30.0), null)
        }
        assertTrue("speed" in e.message!!, e.message)
    }

    @Test
    fun tooLittlePilotDataIsAFitError() {
        val noPilot = json.substringBefore("\"pilot\"") + "\"kernel\"" + json.substringAfter("\"kernel\"")
        val e = assertFailsWith<TrailprintException.Fit> { fitBuildingKernel(noPilot, "bare.json") }
        assertTrue("3 or more" in e.message!!, e.message)
    }
}
