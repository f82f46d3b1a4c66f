package dev.trailprint

import dev.trailprint.permissions.AppPermission
import dev.trailprint.permissions.SurveyPermissions
import dev.trailprint.robot.CleartextPolicy
import dev.trailprint.survey.SurveyMode
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertFalse
import kotlin.test.assertNotNull
import kotlin.test.assertNull
import kotlin.test.assertTrue

/** Issue 19: permissions asked when a survey starts, and what happens when refused. */
class PermissionsTest {
    private val location = AppPermission.LOCATION.manifestName
    private val steps = AppPermission.ACTIVITY_RECOGNITION.manifestName
    private val notify = AppPermission.NOTIFICATIONS.manifestName

    @Test
    fun aSurveyAsksOnlyForWhatItsModeAndAndroidVersionUse() {
        assertEquals(listOf(AppPermission.LOCATION, AppPermission.ACTIVITY_RECOGNITION, AppPermission.NOTIFICATIONS), SurveyPermissions.wanted(SurveyMode.HUMAN, 35))
        assertEquals(listOf(AppPermission.LOCATION, AppPermission.NOTIFICATIONS), SurveyPermissions.wanted(SurveyMode.ROBOT, 35))
        // Android 8: no step or notification permission exists yet.
        assertEquals(listOf(AppPermission.LOCATION), SurveyPermissions.wanted(SurveyMode.HUMAN, 26))
        assertEquals(listOf(AppPermission.NOTIFICATIONS), SurveyPermissions.toAsk(SurveyMode.HUMAN, 34, setOf(location, steps)))
        assertTrue(AppPermission.entries.all { it.reason.isNotBlank() && it.ifRefused.isNotBlank() })
    }

    @Test
    fun refusalsDegradeWithAMessageAndOnlyLocationBlocksASurvey() {
        val all = SurveyPermissions.outcome(SurveyMode.HUMAN, 35, setOf(location, steps, notify))
        assertTrue(all.canStart && all.useStepDetector && all.showNotification && all.notes.isEmpty())
        val noSteps = SurveyPermissions.outcome(SurveyMode.HUMAN, 35, setOf(location, notify))
        assertTrue(noSteps.canStart)
        assertFalse(noSteps.useStepDetector, "the accelerometer takes over")
        assertEquals(listOf(AppPermission.ACTIVITY_RECOGNITION.ifRefused), noSteps.notes)
        val noNotify = SurveyPermissions.outcome(SurveyMode.ROBOT, 35, setOf(location))
        assertTrue(noNotify.canStart && !noNotify.showNotification)
        assertTrue("notification is hidden" in noNotify.notes.single())
        val noLocation = SurveyPermissions.outcome(SurveyMode.HUMAN, 35, setOf(steps, notify))
        assertFalse(noLocation.canStart)
        assertTrue("no fingerprints" in noLocation.blocker!!, noLocation.blocker)
        // Before Android 13 there is nothing to refuse about notifications.
        assertTrue(SurveyPermissions.outcome(SurveyMode.ROBOT, 30, setOf(location)).showNotification)
    }

    @Test
    fun locationIsAskedPreciseAndApproximateTogetherAndApproximateOnlyIsExplained() {
        val coarse = SurveyPermissions.COARSE_LOCATION
        // One request carries both, so that Android 12+ shows its precise/approximate choice
        // (it ignores a request for fine location alone).
        val first = SurveyPermissions.request(SurveyPermissions.toAsk(SurveyMode.HUMAN, 35, emptySet()))
        assertEquals(listOf(location, coarse, steps, notify), first)
        assertTrue(coarse in SurveyPermissions.checked)
        // The surveyor picked "Approximate": no survey, and the message says what to turn on.
        val approx = SurveyPermissions.outcome(SurveyMode.HUMAN, 31, setOf(coarse, steps, notify))
        assertFalse(approx.canStart)
        assertTrue(approx.approximateOnly)
        assertTrue("precise location" in approx.blocker!! && "Use precise location" in approx.blocker!!, approx.blocker)
        // Asking again offers Android's upgrade to precise; again both names.
        val again = SurveyPermissions.toAsk(SurveyMode.HUMAN, 31, setOf(coarse, steps, notify))
        assertEquals(listOf(AppPermission.LOCATION), again)
        assertEquals(listOf(location, coarse), SurveyPermissions.request(again))
        // Android 9 gives scan results with approximate location: the survey starts.
        val pie = SurveyPermissions.outcome(SurveyMode.HUMAN, 28, setOf(coarse))
        assertTrue(pie.canStart && !pie.approximateOnly && pie.blocker == null)
        assertEquals(emptyList(), SurveyPermissions.toAsk(SurveyMode.HUMAN, 28, setOf(coarse)))
        // Refused outright: the ordinary message, not the approximate one.
        val none = SurveyPermissions.outcome(SurveyMode.ROBOT, 35, setOf(notify))
        assertFalse(none.canStart || none.approximateOnly)
        assertEquals(AppPermission.LOCATION.ifRefused, none.blocker)
    }

    @Test
    fun plainWebSocketsOnlyToLocalNames() {
        for (ok in listOf("ws://localhost:9090", "ws://127.0.0.1:9090", "ws://10.0.2.2:9090", "ws://turtlebot.local:9090", "wss://robot.example.org/ros", "ws://Robot.Local.:9090")) {
            assertNull(CleartextPolicy.check(ok), ok)
        }
        val lan = CleartextPolicy.check("ws://192.168.1.20:9090")
        assertNotNull(lan)
        assertTrue("192.168.1.20" in lan && "network_security_config" in lan, lan)
        assertTrue("ws:// or wss://" in CleartextPolicy.check("http://robot.local:9090")!!)
        assertTrue("not a URL" in CleartextPolicy.check("ws://bad host")!!)
    }
}
