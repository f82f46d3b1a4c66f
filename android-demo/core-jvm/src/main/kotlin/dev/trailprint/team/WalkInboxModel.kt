package dev.trailprint.team

import dev.trailprint.AppException
import dev.trailprint.Trailprint
import dev.trailprint.runAction
import kotlinx.coroutines.CoroutineDispatcher
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asStateFlow
import kotlinx.coroutines.flow.update
import kotlinx.coroutines.launch
import kotlinx.coroutines.withContext

data class WalkInboxState(
    val busy: Boolean = false,
    /** The walk file just opened: its plan is saved and ready to walk. */
    val received: ReceivedWalk? = null,
    /** The walk files kept on this phone, "Not opened" first (empty without an inbox). */
    val inbox: List<InboxEntry> = emptyList(),
    /** A walk file waiting for the surveyor's answer: open it as a plan to walk, or later. */
    val pending: InboxEntry? = null,
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

    /** The question of the "open this walk?" dialog, for [pending]. */
    fun pendingQuestion(): String? = pending?.let { p ->
        val a = p.assignment
        "${p.name}: walk ${a.member} of ${a.members}" + (a.surveyorName?.let { " for $it" } ?: "") +
            " in ${a.building}, from ${a.start} to ${a.end}, %.0f m. Open it as the plan to walk? ".format(a.lengthM) +
            "Later keeps it under Walk files as \"Not opened\"."
    }
}

/**
 * A surveyor's phone receiving walk files (from the share sheet, a file picker or a file
 * manager's "open with"). With an [inbox], a received file is kept first ([receive]) and
 * the surveyor is asked whether to open it now ([WalkInboxState.pending]); "Later" leaves
 * it "Not opened" in the list, from where it can be opened any time ([ask], [openPending]).
 * Opening saves the walk as a plan (importing the file's bundle) and the screen offers to
 * start the survey on [WalkInboxState.received]'s plan.
 */
class WalkInboxModel(
    private val api: Trailprint,
    private val scope: CoroutineScope,
    private val inbox: WalkInbox? = null,
    private val io: CoroutineDispatcher = Dispatchers.IO,
) {
    private val _state = MutableStateFlow(WalkInboxState())
    val state: StateFlow<WalkInboxState> = _state.asStateFlow()

    /** Opens the walk file [text] at once, without keeping it. */
    fun open(origin: String, text: String) = scope.launch {
        runAction(
            start = { _state.update { it.copy(busy = true, received = null, error = null) } },
            fail = ::showError,
            finish = { _state.update { it.copy(busy = false) } },
        ) {
            val r = WalkFiles.open(api, text, origin)
            _state.update { it.copy(received = r) }
        }
    }

    /** Reloads the kept walk files. */
    fun refresh() = act { }

    /**
     * Keeps the walk files [files] (name, text) in the inbox, "Not opened". When [ask] is
     * true (the surveyor is not in a survey), the first one becomes [WalkInboxState.pending].
     * A file that is not a walk file is refused with the field; the others are still kept.
     */
    fun receive(files: List<Pair<String, String>>, ask: Boolean = true) = act {
        val box = requireInbox()
        val errors = mutableListOf<String>()
        val kept = files.mapNotNull { (name, text) ->
            try {
                withContext(io) { box.add(name, text) }
            } catch (e: AppException) {
                errors += e.message ?: name
                null
            }
        }
        _state.update { s ->
            s.copy(pending = if (ask) kept.firstOrNull { !it.opened } ?: s.pending else s.pending, error = errors.joinToString("\n").ifEmpty { null })
        }
    }

    /** Asks about [entry] (a tap on a "Not opened" line). */
    fun ask(entry: InboxEntry) = _state.update { it.copy(pending = entry) }

    /** "Later": the pending walk stays "Not opened". */
    fun later() = _state.update { it.copy(pending = null) }

    /** Opens the pending walk as a plan to walk, and marks it opened. */
    fun openPending() = act {
        val box = requireInbox()
        val p = _state.value.pending ?: return@act
        _state.update { it.copy(pending = null, received = null) }
        val text = withContext(io) { box.text(p.id) }
        val r = WalkFiles.open(api, text, p.name)
        withContext(io) { box.markOpened(p.id, r.plan.id) }
        _state.update { it.copy(received = r) }
    }

    /** Deletes a kept walk file (the plan it was opened as stays). */
    fun remove(entry: InboxEntry) = act {
        withContext(io) { requireInbox().remove(entry.id) }
        _state.update { s -> s.copy(pending = s.pending?.takeIf { it.id != entry.id }) }
    }

    fun dismissError() = _state.update { it.copy(error = null) }

    private fun requireInbox(): WalkInbox = inbox ?: throw AppException("this screen keeps no walk files")

    /** Runs [block], then reloads the list; errors become [WalkInboxState.error]. */
    private fun act(block: suspend () -> Unit) = scope.launch {
        runAction(
            start = { _state.update { it.copy(busy = true) } },
            fail = ::showError,
            finish = {
                val list = inbox?.let { box -> withContext(io) { runCatching { box.entries() }.getOrElse { emptyList() } } } ?: emptyList()
                _state.update { it.copy(busy = false, inbox = list) }
            },
            block = block,
        )
    }

    private fun showError(message: String?) = _state.update { it.copy(error = message) }
}
