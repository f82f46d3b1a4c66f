package dev.trailprint.app.ui

import android.app.Application
import android.net.Uri
import android.provider.OpenableColumns
import androidx.activity.compose.rememberLauncherForActivityResult
import androidx.activity.result.contract.ActivityResultContracts
import androidx.compose.foundation.clickable
import androidx.compose.foundation.layout.Arrangement
import androidx.compose.foundation.layout.Column
import androidx.compose.foundation.layout.Row
import androidx.compose.foundation.layout.fillMaxSize
import androidx.compose.foundation.layout.fillMaxWidth
import androidx.compose.foundation.layout.padding
import androidx.compose.foundation.lazy.LazyColumn
import androidx.compose.foundation.lazy.items
import androidx.compose.material3.AlertDialog
import androidx.compose.material3.Button
import androidx.compose.material3.LinearProgressIndicator
import androidx.compose.material3.OutlinedButton
import androidx.compose.material3.Text
import androidx.compose.material3.TextButton
import androidx.compose.runtime.Composable
import androidx.compose.runtime.LaunchedEffect
import androidx.compose.runtime.getValue
import androidx.compose.ui.Modifier
import androidx.compose.ui.unit.dp
import androidx.lifecycle.AndroidViewModel
import androidx.lifecycle.compose.collectAsStateWithLifecycle
import androidx.lifecycle.viewModelScope
import androidx.lifecycle.viewmodel.compose.viewModel
import androidx.compose.ui.platform.LocalContext
import dev.trailprint.app.TrailprintApp
import dev.trailprint.app.readIncoming
import dev.trailprint.files.Incoming
import dev.trailprint.files.takeEachBatch
import dev.trailprint.ui.BuildingsModel
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.launch
import kotlinx.coroutines.withContext

/** The buildings screen's ViewModel: the Android-free [BuildingsModel] on viewModelScope. */
class BuildingsViewModel(app: Application) : AndroidViewModel(app) {
    private val trailprint = app as TrailprintApp
    val model = BuildingsModel(trailprint.api, viewModelScope)

    init {
        model.refresh()
        // Building files shared to the app from another one.
        viewModelScope.launch {
            trailprint.incomingBuildings.takeEachBatch { files -> files.forEach { model.import(it.text, it.name).join() } }
        }
    }

    fun importDemo() = viewModelScope.launch {
        val json = withContext(Dispatchers.IO) { trailprint.demoBuildingJson() }
        model.import(json, "demo-building.json", replace = true)
    }

    /** Reads a picked document and imports it under its display name. */
    fun importUri(uri: Uri) = viewModelScope.launch {
        val resolver = getApplication<Application>().contentResolver
        val (name, json) = withContext(Dispatchers.IO) {
            val name = resolver.query(uri, arrayOf(OpenableColumns.DISPLAY_NAME), null, null, null)?.use { c ->
                if (c.moveToFirst()) c.getString(0) else null
            } ?: uri.lastPathSegment ?: "building.json"
            name to (resolver.openInputStream(uri)?.bufferedReader()?.use { it.readText() } ?: "")
        }
        model.import(json, name)
    }

    /** A picked walk file: kept in the walk inbox and asked about; anything else refused by name. */
    fun receiveWalk(uri: Uri, then: () -> Unit) = viewModelScope.launch {
        when (val f = withContext(Dispatchers.IO) { getApplication<Application>().readIncoming(uri) }) {
            is Incoming.Walk -> {
                trailprint.walks.receive(listOf(f.name to f.text))
                then()
            }
            is Incoming.Refused -> model.reportError(f.line())
            else -> model.reportError("${f.name}: not a walk file (open bundles under Coordinate a team, buildings with Import file)")
        }
    }
}

@Composable
fun BuildingsScreen(onOpen: (Long) -> Unit, onTeam: () -> Unit, onWalkFiles: () -> Unit, onPastSurveys: () -> Unit, vm: BuildingsViewModel = viewModel()) {
    val state by vm.model.state.collectAsStateWithLifecycle()
    val context = LocalContext.current
    val walks by (context.applicationContext as TrailprintApp).walks.state.collectAsStateWithLifecycle()
    val picker = rememberLauncherForActivityResult(ActivityResultContracts.OpenDocument()) { uri -> uri?.let(vm::importUri) }
    // A walk file from the coordinator: kept in the walk inbox, then the walk screen asks.
    val walkPicker = rememberLauncherForActivityResult(ActivityResultContracts.OpenDocument()) { uri ->
        uri?.let { vm.receiveWalk(it, onWalkFiles) }
    }
    LaunchedEffect(Unit) { (context.applicationContext as TrailprintApp).walks.refresh() }
    Column(Modifier.fillMaxSize().padding(16.dp), verticalArrangement = Arrangement.spacedBy(12.dp)) {
        Text("Buildings", style = androidx.compose.material3.MaterialTheme.typography.headlineMedium)
        Row(horizontalArrangement = Arrangement.spacedBy(8.dp)) {
            Button(onClick = { picker.launch(arrayOf("application/json", "*/*")) }) { Text("Import file") }
            OutlinedButton(onClick = { vm.importDemo() }) { Text("Load demo building") }
        }
        Row(horizontalArrangement = Arrangement.spacedBy(8.dp)) {
            OutlinedButton(onClick = { walkPicker.launch(arrayOf("application/json", "*/*")) }) { Text("Open a walk file") }
            OutlinedButton(onClick = onTeam) { Text("Coordinate a team") }
        }
        Row(horizontalArrangement = Arrangement.spacedBy(8.dp)) {
            val waiting = walks.inbox.count { !it.opened }
            OutlinedButton(onClick = onWalkFiles) { Text(if (waiting > 0) "Walk files ($waiting not opened)" else "Walk files") }
            OutlinedButton(onClick = onPastSurveys) { Text("Past surveys") }
        }
        if (state.busy) LinearProgressIndicator(Modifier.fillMaxWidth())
        LazyColumn(verticalArrangement = Arrangement.spacedBy(8.dp)) {
            items(state.buildings, key = { it.id }) { b ->
                Column(Modifier.fillMaxWidth().clickable { onOpen(b.id) }.padding(8.dp)) {
                    Text(b.name, style = androidx.compose.material3.MaterialTheme.typography.titleMedium)
                    Text("${b.vertices} vertices, ${b.edges} edges, ${b.pilot} pilot points, ${b.plans} plans, ${b.collected} fingerprints")
                }
            }
        }
    }
    state.error?.let { msg ->
        AlertDialog(
            onDismissRequest = vm.model::dismissError,
            confirmButton = { TextButton(onClick = vm.model::dismissError) { Text("OK") } },
            title = { Text("Cannot import") },
            text = { Text(msg) },
        )
    }
}
