package dev.trailprint.app.ui

import android.app.Application
import androidx.compose.foundation.layout.Arrangement
import androidx.compose.foundation.layout.Column
import androidx.compose.foundation.layout.fillMaxSize
import androidx.compose.foundation.layout.fillMaxWidth
import androidx.compose.foundation.layout.padding
import androidx.compose.material3.Button
import androidx.compose.material3.LinearProgressIndicator
import androidx.compose.material3.MaterialTheme
import androidx.compose.material3.OutlinedButton
import androidx.compose.material3.Text
import androidx.compose.runtime.Composable
import androidx.compose.runtime.getValue
import androidx.compose.ui.Modifier
import androidx.compose.ui.unit.dp
import androidx.lifecycle.AndroidViewModel
import androidx.lifecycle.compose.collectAsStateWithLifecycle
import androidx.lifecycle.viewModelScope
import androidx.lifecycle.viewmodel.compose.viewModel
import dev.trailprint.app.TrailprintApp
import dev.trailprint.team.WalkInboxModel
import kotlinx.coroutines.launch

/** A surveyor's phone receiving a walk file: the Android-free [WalkInboxModel]. */
class WalkViewModel(app: Application) : AndroidViewModel(app) {
    private val trailprint = app as TrailprintApp
    val model = WalkInboxModel(trailprint.api, viewModelScope)

    init {
        viewModelScope.launch {
            trailprint.incoming.collect { files ->
                files.firstOrNull()?.let { f ->
                    trailprint.incoming.value = emptyList()
                    model.open(f.name, f.text)
                }
            }
        }
    }
}

@Composable
fun WalkScreen(onStart: (planId: Long) -> Unit, onBack: () -> Unit, vm: WalkViewModel = viewModel()) {
    val s by vm.model.state.collectAsStateWithLifecycle()
    Column(Modifier.fillMaxSize().padding(16.dp), verticalArrangement = Arrangement.spacedBy(10.dp)) {
        Text("Your walk", style = MaterialTheme.typography.headlineMedium)
        if (s.busy) LinearProgressIndicator(Modifier.fillMaxWidth())
        s.lines().forEach { Text(it) }
        s.error?.let { Text(it, color = MaterialTheme.colorScheme.error) }
        s.received?.let { r -> Button(onClick = { onStart(r.plan.id) }) { Text("Start this survey") } }
        OutlinedButton(onClick = onBack) { Text("Back to buildings") }
    }
}
