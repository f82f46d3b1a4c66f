package dev.trailprint.app.ui

import android.app.Application
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
import androidx.compose.material3.Checkbox
import androidx.compose.material3.LinearProgressIndicator
import androidx.compose.material3.MaterialTheme
import androidx.compose.material3.Text
import androidx.compose.material3.TextButton
import androidx.compose.runtime.Composable
import androidx.compose.runtime.LaunchedEffect
import androidx.compose.runtime.getValue
import androidx.compose.ui.Alignment
import androidx.compose.ui.Modifier
import androidx.compose.ui.platform.LocalContext
import androidx.compose.ui.unit.dp
import androidx.lifecycle.AndroidViewModel
import androidx.lifecycle.compose.collectAsStateWithLifecycle
import androidx.lifecycle.viewModelScope
import androidx.lifecycle.viewmodel.compose.viewModel
import dev.trailprint.app.TrailprintApp
import dev.trailprint.app.shareFiles
import dev.trailprint.ui.PastSurveysModel

class PastSurveysViewModel(app: Application) : AndroidViewModel(app) {
    private val trailprint = app as TrailprintApp
    val model = PastSurveysModel(trailprint.api, trailprint.exports, viewModelScope)

    init {
        model.refresh()
    }
}

/** Finished surveys, shared again: CSV or JSON of one, bundles of the ticked ones. */
@Composable
fun PastSurveysScreen(vm: PastSurveysViewModel = viewModel()) {
    val s by vm.model.state.collectAsStateWithLifecycle()
    val m = vm.model
    val context = LocalContext.current
    val app = context.applicationContext as TrailprintApp
    LaunchedEffect(s.share) { if (s.share.isNotEmpty()) { context.shareFiles(s.share); m.shared() } }
    Column(Modifier.fillMaxSize().padding(12.dp), verticalArrangement = Arrangement.spacedBy(8.dp)) {
        Text("Past surveys", style = MaterialTheme.typography.headlineMedium)
        if (s.busy) LinearProgressIndicator(Modifier.fillMaxWidth())
        if (s.surveys.isEmpty() && !s.busy) Text("No finished survey on this phone yet.")
        Button(onClick = { m.shareSelectedBundles(app.deviceName, app.surveyorName) }, enabled = s.selected.isNotEmpty() && !s.busy) {
            Text("Share ${s.selected.size} as bundles")
        }
        LazyColumn(verticalArrangement = Arrangement.spacedBy(4.dp)) {
            items(s.surveys, key = { it.sessionId }) { p ->
                Row(verticalAlignment = Alignment.CenterVertically) {
                    Checkbox(p.sessionId in s.selected, { m.toggle(p.sessionId) })
                    Text(p.line(), Modifier.weight(1f), style = MaterialTheme.typography.bodySmall)
                    TextButton(onClick = { m.shareCsv(p.sessionId) }) { Text("CSV") }
                    TextButton(onClick = { m.shareJson(p.sessionId) }) { Text("JSON") }
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
