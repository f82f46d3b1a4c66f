package dev.trailprint.app.ui

import android.app.Application
import androidx.activity.compose.rememberLauncherForActivityResult
import androidx.activity.result.contract.ActivityResultContracts
import androidx.compose.foundation.layout.Arrangement
import androidx.compose.foundation.layout.Column
import androidx.compose.foundation.layout.Row
import androidx.compose.foundation.layout.fillMaxSize
import androidx.compose.foundation.layout.fillMaxWidth
import androidx.compose.foundation.layout.height
import androidx.compose.foundation.layout.padding
import androidx.compose.foundation.horizontalScroll
import androidx.compose.foundation.rememberScrollState
import androidx.compose.foundation.verticalScroll
import androidx.compose.material3.AlertDialog
import androidx.compose.material3.Button
import androidx.compose.material3.FilterChip
import androidx.compose.material3.LinearProgressIndicator
import androidx.compose.material3.MaterialTheme
import androidx.compose.material3.OutlinedButton
import androidx.compose.material3.OutlinedTextField
import androidx.compose.material3.Text
import androidx.compose.material3.TextButton
import androidx.compose.runtime.Composable
import androidx.compose.runtime.LaunchedEffect
import androidx.compose.runtime.getValue
import androidx.compose.runtime.mutableStateOf
import androidx.compose.runtime.remember
import androidx.compose.runtime.setValue
import androidx.compose.ui.Modifier
import androidx.compose.ui.platform.LocalContext
import androidx.compose.ui.unit.dp
import androidx.lifecycle.AndroidViewModel
import androidx.lifecycle.compose.collectAsStateWithLifecycle
import androidx.lifecycle.viewModelScope
import androidx.lifecycle.viewmodel.compose.viewModel
import dev.trailprint.app.TrailprintApp
import dev.trailprint.app.readDocument
import dev.trailprint.app.shareFile
import dev.trailprint.files.takeEachBatch
import dev.trailprint.team.CoordinatorModel
import android.net.Uri
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.launch
import kotlinx.coroutines.withContext

/** The coordinator's screen: the Android-free [CoordinatorModel] on viewModelScope. */
class TeamViewModel(app: Application) : AndroidViewModel(app) {
    private val trailprint = app as TrailprintApp
    val model = CoordinatorModel(trailprint.api, trailprint.exports, viewModelScope, trailprint.deviceName, trailprint.surveyorName)

    init {
        model.refresh()
        // Bundles shared to the app from another one (the share sheet) wait in TrailprintApp.
        viewModelScope.launch {
            trailprint.incomingBundles.takeEachBatch { files -> model.importBundles(files.map { it.name to it.text }) }
        }
    }

    fun importUris(uris: List<Uri>) = viewModelScope.launch {
        try {
            val files = withContext(Dispatchers.IO) { uris.map { getApplication<Application>().readDocument(it) } }
            model.importBundles(files.map { it.name to it.text })
        } catch (e: java.io.IOException) {
            model.reportError("Cannot read the file: ${e.message}")
        }
    }
}

@Composable
fun TeamScreen(vm: TeamViewModel = viewModel()) {
    val s by vm.model.state.collectAsStateWithLifecycle()
    val m = vm.model
    val context = LocalContext.current
    val picker = rememberLauncherForActivityResult(ActivityResultContracts.OpenMultipleDocuments()) { vm.importUris(it) }
    var count by remember { mutableStateOf("2") }
    var budget by remember { mutableStateOf("60") }
    var start by remember { mutableStateOf<String?>(null) }
    var end by remember { mutableStateOf<String?>(null) }
    LaunchedEffect(s.share) { s.share?.let { context.shareFile(it); m.shared() } }
    Column(Modifier.fillMaxSize().padding(12.dp).verticalScroll(rememberScrollState()), verticalArrangement = Arrangement.spacedBy(8.dp)) {
        Text("Team survey", style = MaterialTheme.typography.headlineMedium)
        Button(onClick = { picker.launch(arrayOf("application/json", "application/octet-stream", "*/*")) }) { Text("Import bundles") }
        if (s.busy) LinearProgressIndicator(Modifier.fillMaxWidth())
        s.receipts.forEach { Text(it.line(), style = MaterialTheme.typography.bodySmall) }
        Row(Modifier.horizontalScroll(rememberScrollState()), horizontalArrangement = Arrangement.spacedBy(4.dp)) {
            s.buildings.forEach { b -> FilterChip(b.id == s.buildingId, { m.selectBuilding(b.id) }, { Text("${b.name} (${b.collected})") }) }
        }
        s.map?.let { map ->
            Text("Start: ${start ?: "tap a vertex"}   End: ${end ?: "tap a vertex"}")
            MapCanvas(map, MapOverlay(highlighted = setOfNotNull(start, end)), Modifier.fillMaxWidth().height(260.dp), onVertexTap = { v ->
                if (start == null || end != null) { start = v; end = null } else end = v
            })
        }
        Row(horizontalArrangement = Arrangement.spacedBy(8.dp)) {
            OutlinedTextField(count, { count = it }, label = { Text("Surveyors") }, singleLine = true, modifier = Modifier.weight(1f))
            OutlinedTextField(budget, { budget = it }, label = { Text("Metres each") }, singleLine = true, modifier = Modifier.weight(1f))
        }
        val n = count.toIntOrNull()
        val b = budget.toDoubleOrNull()
        Button(
            onClick = {
                m.setTeam(n!!, start!!, end!!, b!!)
                m.plan()
            },
            enabled = !s.busy && s.buildingId != null && start != null && end != null && n != null && n in 1..50 && b != null && b > 0,
        ) { Text("Plan the team's walks") }
        s.planProgress?.let { line ->
            Row(horizontalArrangement = Arrangement.spacedBy(8.dp)) {
                Text(line, Modifier.weight(1f), style = MaterialTheme.typography.bodySmall)
                OutlinedButton(onClick = m::stopPlanning) { Text("Stop") }
            }
        }
        s.team?.let { t ->
            Text(t.label, style = MaterialTheme.typography.titleMedium)
            Text("Team: %.2f nats together".format(t.summary.teamUtilityNats))
            t.assignments.zip(t.files).forEach { (a, f) ->
                Row(horizontalArrangement = Arrangement.spacedBy(8.dp)) {
                    Text("${a.member}. ${a.surveyorName ?: ""}: ${"%.0f".format(a.lengthM)} m, ${a.walk.size} vertices", Modifier.weight(1f))
                    OutlinedButton(onClick = { m.share(f) }) { Text("Share walk") }
                }
            }
        }
    }
    s.error?.let { msg ->
        AlertDialog(
            onDismissRequest = m::dismissError,
            confirmButton = { TextButton(onClick = m::dismissError) { Text("OK") } },
            text = { Text(msg) },
        )
    }
}
