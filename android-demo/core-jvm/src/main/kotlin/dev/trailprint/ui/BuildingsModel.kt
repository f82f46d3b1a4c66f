package dev.trailprint.ui

import dev.trailprint.Trailprint
import dev.trailprint.ffi.BuildingSummary
import dev.trailprint.runBusy
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asStateFlow
import kotlinx.coroutines.flow.update
import kotlinx.coroutines.launch

/** The buildings screen: the list, an import in progress, the last error. */
data class BuildingsState(
    val buildings: List<BuildingSummary> = emptyList(),
    val busy: Boolean = false,
    val error: String? = null,
)

/**
 * State of the buildings screen (Android-free; the Android ViewModel passes its
 * viewModelScope). Import errors keep the list and show the core's message, which names
 * the file and the JSON path.
 */
class BuildingsModel(private val api: Trailprint, private val scope: CoroutineScope) {
    private val _state = MutableStateFlow(BuildingsState())
    val state: StateFlow<BuildingsState> = _state.asStateFlow()

    fun refresh() = launchBusy { _state.update { it.copy(buildings = api.buildings()) } }

    /** Imports building JSON read from a file the user picked; [origin] is its name. */
    fun import(json: String, origin: String, replace: Boolean = false) = launchBusy {
        api.importBuilding(json, origin, replace)
        _state.update { it.copy(buildings = api.buildings()) }
    }

    fun delete(buildingId: Long) = launchBusy {
        api.deleteBuilding(buildingId)
        _state.update { it.copy(buildings = api.buildings()) }
    }

    fun dismissError() = _state.update { it.copy(error = null) }

    /** Shows an error from outside the store (a file that could not be read). */
    fun reportError(message: String) = _state.update { it.copy(error = message) }

    private fun launchBusy(block: suspend () -> Unit) = scope.launch { _state.runBusy({ copy(busy = it) }, { copy(error = it) }, block) }
}
