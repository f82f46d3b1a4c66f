package dev.trailprint.permissions

import dev.trailprint.survey.SurveyMode

/**
 * The runtime permissions a survey uses, with the line the app shows when it asks and the
 * line it shows when the answer is no. [sinceSdk] is the Android API level from which
 * the permission exists as a runtime permission.
 */
enum class AppPermission(val manifestName: String, val sinceSdk: Int, val reason: String, val ifRefused: String) {
    LOCATION(
        "android.permission.ACCESS_FINE_LOCATION",
        23,
        "Wi-Fi scan results reveal where the phone is, so Android gives them only to apps allowed to use location. " +
            "Trailprint needs them to record fingerprints; it does not use GPS.",
        "Without location permission the phone reports no Wi-Fi scans, so a survey would collect no fingerprints. " +
            "Allow location in Settings → Apps → Trailprint → Permissions to survey.",
    ),
    ACTIVITY_RECOGNITION(
        "android.permission.ACTIVITY_RECOGNITION",
        29,
        "The step detector counts your steps, which tells the survey how far you walked between check-ins.",
        "Steps are counted from the accelerometer instead: a little less exact, and the phone's CPU stays awake for the whole survey.",
    ),
    NOTIFICATIONS(
        "android.permission.POST_NOTIFICATIONS",
        33,
        "The survey keeps running with the screen off; its notification shows the progress and has a Stop button.",
        "The survey still runs, but its notification is hidden: open Trailprint to see the progress or to stop it.",
    ),
}

/** What the answers allow: whether the survey can start, and what the surveyor should know. */
data class PermissionOutcome(
    val canStart: Boolean,
    /** Why it cannot start (null when it can). */
    val blocker: String?,
    /** One line per refused permission the survey can do without. */
    val notes: List<String>,
    /** Steps from the hardware step detector (else the accelerometer). */
    val useStepDetector: Boolean,
    val showNotification: Boolean,
)

/**
 * Which permissions a survey asks for, at the moment it starts (not when the app opens),
 * and what it does when some are refused. Android-free: the app passes its API level and
 * the permissions granted; the host tests cover every combination that matters.
 */
object SurveyPermissions {
    /** The permissions [mode] uses on API level [sdk]. */
    fun wanted(mode: SurveyMode, sdk: Int): List<AppPermission> = AppPermission.entries.filter { p ->
        sdk >= p.sinceSdk && (p != AppPermission.ACTIVITY_RECOGNITION || mode == SurveyMode.HUMAN)
    }

    /** The ones still to ask for, given the [granted] manifest names. */
    fun toAsk(mode: SurveyMode, sdk: Int, granted: Set<String>): List<AppPermission> =
        wanted(mode, sdk).filter { it.manifestName !in granted }

    /** What the survey can do with the [granted] permissions. */
    fun outcome(mode: SurveyMode, sdk: Int, granted: Set<String>): PermissionOutcome {
        val refused = toAsk(mode, sdk, granted)
        val location = AppPermission.LOCATION !in refused
        return PermissionOutcome(
            canStart = location,
            blocker = if (location) null else AppPermission.LOCATION.ifRefused,
            notes = refused.filter { it != AppPermission.LOCATION }.map { it.ifRefused },
            useStepDetector = mode == SurveyMode.HUMAN && AppPermission.ACTIVITY_RECOGNITION !in refused,
            showNotification = AppPermission.NOTIFICATIONS !in refused,
        )
    }
}
