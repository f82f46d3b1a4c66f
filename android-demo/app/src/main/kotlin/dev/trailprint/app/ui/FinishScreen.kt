package dev.trailprint.app.ui

import android.app.Application
import androidx.compose.foundation.layout.Arrangement
import androidx.compose.foundation.layout.Column
import androidx.compose.foundation.layout.Row
import androidx.compose.foundation.layout.fillMaxSize
import androidx.compose.foundation.layout.fillMaxWidth
import androidx.compose.foundation.layout.padding
import androidx.compose.material3.Button
import androidx.compose.material3.LinearProgressIndicator
import androidx.compose.material3.MaterialTheme
import androidx.compose.material3.OutlinedButton
import androidx.compose.material3.OutlinedTextField
import androidx.compose.material3.Text
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
import androidx.lifecycle.ViewModelProvider.AndroidViewModelFactory.Companion.APPLICATION_KEY
import androidx.lifecycle.compose.collectAsStateWithLifecycle
import androidx.lifecycle.viewModelScope
import androidx.lifecycle.viewmodel.compose.viewModel
import androidx.lifecycle.viewmodel.initializer
import androidx.lifecycle.viewmodel.viewModelFactory
import dev.trailprint.app.TrailprintApp
import dev.trailprint.app.shareFile
import dev.trailprint.ui.FinishModel

class FinishViewModel(app: Application, sessionId: Long) : AndroidViewModel(app) {
    private val trailprint = app as TrailprintApp
    val model = FinishModel(trailprint.api, trailprint.exports, viewModelScope)

    init {
        model.load(sessionId)
    }

    companion object {
        fun factory(sessionId: Long) = viewModelFactory {
            initializer { FinishViewModel(this[APPLICATION_KEY]!!, sessionId) }
        }
    }
}

/** The summary, and the survey's data shared as files (CSV, JSON, the bundle for the coordinator). */
@Composable
fun FinishScreen(sessionId: Long, onDone: () -> Unit, vm: FinishViewModel = viewModel(key = "finish-$sessionId", factory = FinishViewModel.factory(sessionId))) {
    val s by vm.model.state.collectAsStateWithLifecycle()
    val context = LocalContext.current
    val app = context.applicationContext as TrailprintApp
    var surveyor by remember { mutableStateOf(app.surveyorName ?: "") }
    LaunchedEffect(s.share) {
        s.share?.let { context.shareFile(it); vm.model.shared() }
    }
    Column(Modifier.fillMaxSize().padding(16.dp), verticalArrangement = Arrangement.spacedBy(10.dp)) {
        Text("Survey done", style = MaterialTheme.typography.headlineMedium)
        s.lines().forEach { Text(it) }
        s.error?.let { Text(it, color = MaterialTheme.colorScheme.error) }
        if (s.busy) LinearProgressIndicator(Modifier.fillMaxWidth())
        Row(horizontalArrangement = Arrangement.spacedBy(8.dp)) {
            Button(onClick = vm.model::shareCsv, enabled = !s.busy) { Text("Share CSV") }
            OutlinedButton(onClick = vm.model::shareJson, enabled = !s.busy) { Text("Share JSON") }
        }
        OutlinedTextField(surveyor, { surveyor = it }, label = { Text("Your name (in the bundle)") }, singleLine = true, modifier = Modifier.fillMaxWidth())
        Button(
            onClick = { app.surveyorName = surveyor.trim(); vm.model.shareBundle(app.deviceName, surveyor) },
            enabled = !s.busy && s.buildingId != null,
        ) { Text("Share with the coordinator (bundle)") }
        OutlinedButton(onClick = onDone) { Text("Back to buildings") }
    }
}
