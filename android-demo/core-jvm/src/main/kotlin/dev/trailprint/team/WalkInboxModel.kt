package dev.trailprint.team

import dev.trailprint.AppException
import dev.trailprint.Trailprint
import dev.trailprint.ffi.TrailprintException
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asStateFlow
import kotlinx.coroutines.flow.update
import kotlinx.coroutines.launch

data class WalkInboxState(
    val busy: Boolean = false,
    /** The walk file just opened: its plan is saved and ready to walk. */
    val received: ReceivedWalk? = null,
    val error: String? = null,
) {
    /** What the surveyor reads before starting. */
    fun lines(): List<String> = received?.let { r ->
        val a = r.assignment
        listOf(
            "Walk ${a.member} of ${a.members}" + (a.surveyorName?.let { " for $it" } ?: ""),
            a.team,
            "%s: from %s to %s, %.0f m (budget %.0f m), %d vertices".format(a.building, a.start, a.end, r.plan.lengthM, a.budgetM, a.walk.size),
            "The team has collected in ${r.imported.sessionsAdded + r.imported.sessionsUnchanged + r.imported.sessionsExtended} sessions so far.",
        )
    } ?: emptyList()
}

/**
 * A surveyor's phone receiving a walk file (from the share sheet, a file picker or a
 * file manager's "open with"): [open] saves the walk as a plan, and the screen offers to
 * start the survey on [WalkInboxState.received]'s plan.
 */
class WalkInboxModel(private val api: Trailprint, private val scope: CoroutineScope) {
    private val _state = MutableStateFlow(WalkInboxState())
    val state: StateFlow<WalkInboxState> = _state.asStateFlow()

    fun open(origin: String, text: String) = scope.launch {
        _state.value = WalkInboxState(busy = true)
        try {
            val r = WalkFiles.open(api, text, origin)
            _state.value = WalkInboxState(received = r)
        } catch (e: AppException) {
            _state.value = WalkInboxState(error = e.message)
        } catch (e: TrailprintException) {
            _state.value = WalkInboxState(error = e.message)
        }
    }

    fun dismissError() = _state.update { it.copy(error = null) }
}
