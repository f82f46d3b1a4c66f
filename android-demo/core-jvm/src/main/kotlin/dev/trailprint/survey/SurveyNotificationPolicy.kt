package dev.trailprint.survey

/** A button of the survey's notification; the service maps each to an intent. */
enum class NotificationAction(val label: String) {
    PAUSE("Pause"),
    RESUME("Resume"),
    FINISH("Finish survey"),
}

/**
 * What the foreground service's notification shows, decided off Android: the service only
 * renders it (`NotificationCompat.Builder`) and maps [actions] to intents.
 */
data class SurveyNotification(
    val title: String,
    val text: String,
    /** A second line for something the surveyor must act on (off the walk, a robot error), or null. */
    val subText: String?,
    /** Progress bar: [progress] of [PROGRESS_MAX]; [indeterminate] until the first progress is known. */
    val progress: Int,
    val indeterminate: Boolean,
    /** Cannot be swiped away while the survey runs or is paused. */
    val ongoing: Boolean,
    val actions: List<NotificationAction>,
) {
    companion object {
        const val PROGRESS_MAX = 1000
    }
}

/**
 * The survey notification from the lifecycle's state, and when to post a new one.
 *
 * Android drops (and rate-limits) notification updates that come faster than a few per
 * second, and a survey's state changes with every step, so progress is posted at most
 * once per [MIN_UPDATE_MS]; a change the surveyor acts on (phase, actions, a warning) is
 * posted at once.
 */
object SurveyNotificationPolicy {
    const val MIN_UPDATE_MS = 1000L

    fun of(state: LifecycleState): SurveyNotification {
        val p = state.live.progress
        val running = state.phase == SurveyPhase.RUNNING
        val paused = state.phase == SurveyPhase.PAUSED
        val title = when (state.phase) {
            SurveyPhase.RUNNING -> "Survey in progress"
            SurveyPhase.PAUSED -> "Survey paused"
            SurveyPhase.FINISHED -> "Survey finished"
            SurveyPhase.ABORTED -> "Survey stopped"
            SurveyPhase.IDLE -> "No survey"
        }
        val text = when {
            // "≥": past its memory budget the session counts one fingerprint of every
            // sampleBlock, so the nats collected are a lower bound.
            p != null -> "%.0f%% of the walk · %d fingerprints · %s%.1f of %.1f nats".format(
                100 * p.fractionDone.coerceIn(0.0, 1.0), p.samples.toLong(), atLeast(p.sampleBlock), p.collectedUtilityNats, p.plannedUtilityNats,
            ) + if (paused) " · tap Resume to walk on" else ""
            state.summary != null -> state.summary.let { s ->
                "%d fingerprints · %s%.1f nats · %.0f m walked".format(s.samples.toLong(), atLeast(s.sampleBlock), s.collectedUtilityNats, s.walkedM)
            }
            state.active != null -> "Session ${state.active.sessionId}: starting…"
            else -> ""
        }
        val warning = when {
            state.live.error != null -> state.live.error
            state.live.guidance?.offRoute == true || p?.offRoute == true -> "Off the planned walk: check in where you are"
            state.message != null && (running || paused) -> state.message
            else -> null
        }
        val actions = when {
            running -> listOf(NotificationAction.PAUSE, NotificationAction.FINISH)
            paused -> listOf(NotificationAction.RESUME, NotificationAction.FINISH)
            else -> emptyList()
        }
        return SurveyNotification(
            title = title,
            text = text,
            subText = warning,
            progress = ((p?.fractionDone ?: state.summary?.let { 1.0 } ?: 0.0).coerceIn(0.0, 1.0) * SurveyNotification.PROGRESS_MAX).toInt(),
            indeterminate = (running || paused) && p == null,
            ongoing = running || paused,
            actions = actions,
        )
    }

    private fun atLeast(sampleBlock: ULong) = if (sampleBlock > 1uL) "≥ " else ""

    /**
     * How long to wait before posting [next], given the notification [posted] last (null:
     * none yet) at [postedAtMs]: null when there is nothing new to post, 0 to post now, else
     * the milliseconds until progress may be updated again (post the latest one then).
     */
    fun delayBeforePost(posted: SurveyNotification?, next: SurveyNotification, postedAtMs: Long, nowMs: Long): Long? {
        if (posted == null) return 0
        if (posted == next) return null
        val urgent = posted.title != next.title || posted.actions != next.actions ||
            posted.ongoing != next.ongoing || posted.subText != next.subText
        if (urgent) return 0
        return (postedAtMs + MIN_UPDATE_MS - nowMs).coerceAtLeast(0)
    }
}
