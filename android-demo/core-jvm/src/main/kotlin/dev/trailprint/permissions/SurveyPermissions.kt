package dev.trailprint.permissions

import dev.trailprint.survey.SurveyMode

/**
 * The runtime permissions a survey uses, with the line the app shows when it asks and the
 * line it shows when the answer is no. [sinceSdk] is the Android API level from which
 * the permission exists as a runtime permission.
 */
enum class AppPermission(
    val manifestName: String,
    val sinceSdk: Int,
    val reason: String,
    val ifRefused: String,
    /** Asked for in the same request as [manifestName] (Android requires the pair). */
    val requestedWith: List<String> = emptyList(),
) {
    /**
     * Precise location, asked for together with approximate: from Android 12 a request for
     * fine location alone is ignored, and the dialog lets the user pick either.
     */
    LOCATION(
        "android.permission.ACCESS_FINE_LOCATION",
        23,
        "Wi-Fi scan results reveal where the phone is, so Android gives them only to apps allowed to use precise location. " +
            "Trailprint needs them to record fingerprints; it does not use GPS.",
        "Without location permission the phone reports no Wi-Fi scans, so a survey would collect no fingerprints. " +
            "Allow location in Settings → Apps → Trailprint → Permissions to survey.",
        requestedWith = listOf(SurveyPermissions.COARSE_LOCATION),
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
        "The survey keeps running with the screen off; its notification shows the progress and has Pause and Finish buttons.",
        "The survey still runs, but its notification is hidden: open Trailprint to see the progress or to stop it.",
    ),
    ;

    /** The manifest names one request for this permission carries. */
    val requested: List<String> get() = listOf(manifestName) + requestedWith
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
    /** Location was granted, but only approximate (Android 12+): scans need precise. */
    val approximateOnly: Boolean = false,
)

/**
 * Which permissions a survey asks for, at the moment it starts (not when the app opens),
 * and what it does when some are refused. Android-free: the app passes its API level and
 * the permissions granted; the host tests cover every combination that matters.
 */
object SurveyPermissions {
    const val COARSE_LOCATION = "android.permission.ACCESS_COARSE_LOCATION"

    /** API level from which Wi-Fi scan results need precise (fine) location (Android 10). */
    const val SCANS_NEED_FINE_SINCE = 29

    /** What the surveyor reads when only approximate location was allowed. */
    const val APPROXIMATE_ONLY =
        "You allowed Trailprint only approximate location. Android hands Wi-Fi scan results only to apps with precise " +
            "location, so a survey would collect no fingerprints. Allow precise location: Settings → Apps → Trailprint → " +
            "Permissions → Location → turn on \"Use precise location\"."

    /** Every manifest name whose grant the app checks (the ones it asks for, and approximate location). */
    val checked: List<String> get() = AppPermission.entries.flatMap { it.requested }.distinct()

    /** The permissions [mode] uses on API level [sdk]. */
    fun wanted(mode: SurveyMode, sdk: Int): List<AppPermission> = AppPermission.entries.filter { p ->
        sdk >= p.sinceSdk && (p != AppPermission.ACTIVITY_RECOGNITION || mode == SurveyMode.HUMAN)
    }

    /** The ones still to ask for, given the [granted] manifest names. */
    fun toAsk(mode: SurveyMode, sdk: Int, granted: Set<String>): List<AppPermission> =
        wanted(mode, sdk).filter { !isGranted(it, sdk, granted) }

    /** The manifest names of one request for [permissions] (fine location always with coarse). */
    fun request(permissions: List<AppPermission>): List<String> = permissions.flatMap { it.requested }.distinct()

    /**
     * Whether [p] counts as granted: location needs the fine grant on Android 10+, where
     * scan results need it; before that approximate is enough for scans.
     */
    private fun isGranted(p: AppPermission, sdk: Int, granted: Set<String>): Boolean =
        p.manifestName in granted ||
            (p == AppPermission.LOCATION && sdk < SCANS_NEED_FINE_SINCE && COARSE_LOCATION in granted)

    /** What the survey can do with the [granted] permissions. */
    fun outcome(mode: SurveyMode, sdk: Int, granted: Set<String>): PermissionOutcome {
        val refused = toAsk(mode, sdk, granted)
        val location = AppPermission.LOCATION !in refused
        val approximateOnly = !location && COARSE_LOCATION in granted
        return PermissionOutcome(
            canStart = location,
            blocker = when {
                location -> null
                approximateOnly -> APPROXIMATE_ONLY
                else -> AppPermission.LOCATION.ifRefused
            },
            notes = refused.filter { it != AppPermission.LOCATION }.map { it.ifRefused },
            useStepDetector = mode == SurveyMode.HUMAN && AppPermission.ACTIVITY_RECOGNITION !in refused,
            showNotification = AppPermission.NOTIFICATIONS !in refused,
            approximateOnly = approximateOnly,
        )
    }
}
