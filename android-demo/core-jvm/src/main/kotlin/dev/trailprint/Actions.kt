package dev.trailprint

import dev.trailprint.ffi.TrailprintException
import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.update

/**
 * One action of a screen model: [start] (marks the state busy), then [block]. The message
 * of an error of the core ([TrailprintException]) or of this layer ([AppException]) goes
 * to [fail], for the screen to show; [finish] (clears busy) runs whatever happened. Any
 * other exception is a bug and propagates.
 */
internal suspend fun runAction(
    start: () -> Unit,
    fail: (String?) -> Unit,
    finish: suspend () -> Unit,
    block: suspend () -> Unit,
) {
    start()
    try {
        block()
    } catch (e: TrailprintException) {
        fail(e.message)
    } catch (e: AppException) {
        fail(e.message)
    } finally {
        finish()
    }
}

/**
 * [runAction] on a screen state with a busy flag and an error line, set by [busy] and
 * [error] (the state's `copy`): busy and no error while [block] runs, its error after.
 */
internal suspend fun <S> MutableStateFlow<S>.runBusy(
    busy: S.(Boolean) -> S,
    error: S.(String?) -> S,
    block: suspend () -> Unit,
) = runAction(
    start = { update { it.busy(true).error(null) } },
    fail = { message -> update { it.error(message) } },
    finish = { update { it.busy(false) } },
    block = block,
)
