package dev.trailprint.app.ui

import android.app.Application
import android.content.Intent
import androidx.compose.foundation.layout.Arrangement
import androidx.compose.foundation.layout.Column
import androidx.compose.foundation.layout.Row
import androidx.compose.foundation.layout.fillMaxSize
import androidx.compose.foundation.layout.padding
import androidx.compose.material3.Button
import androidx.compose.material3.MaterialTheme
import androidx.compose.material3.OutlinedButton
import androidx.compose.material3.Text
import androidx.compose.runtime.Composable
import androidx.compose.runtime.getValue
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
import dev.trailprint.ui.FinishModel

class FinishViewModel(app: Application, sessionId: Long) : AndroidViewModel(app) {
    val model = FinishModel((app as TrailprintApp).api, viewModelScope)

    init {
        model.load(sessionId)
    }

    companion object {
        fun factory(sessionId: Long) = viewModelFactory {
            initializer { FinishViewModel(this[APPLICATION_KEY]!!, sessionId) }
        }
    }
}

@Composable
fun FinishScreen(sessionId: Long, onDone: () -> Unit, vm: FinishViewModel = viewModel(key = "finish-$sessionId", factory = FinishViewModel.factory(sessionId))) {
    val s by vm.model.state.collectAsStateWithLifecycle()
    val context = LocalContext.current
    fun share(text: String, mime: String) {
        val send = Intent(Intent.ACTION_SEND).setType(mime).putExtra(Intent.EXTRA_TEXT, text)
        context.startActivity(Intent.createChooser(send, "Share fingerprints"))
    }
    Column(Modifier.fillMaxSize().padding(16.dp), verticalArrangement = Arrangement.spacedBy(10.dp)) {
        Text("Survey done", style = MaterialTheme.typography.headlineMedium)
        s.lines().forEach { Text(it) }
        s.error?.let { Text(it, color = MaterialTheme.colorScheme.error) }
        Row(horizontalArrangement = Arrangement.spacedBy(8.dp)) {
            s.exportCsv?.let { csv -> Button(onClick = { share(csv, "text/csv") }) { Text("Share CSV") } }
            s.exportJson?.let { json -> OutlinedButton(onClick = { share(json, "application/json") }) { Text("Share JSON") } }
        }
        OutlinedButton(onClick = onDone) { Text("Back to buildings") }
    }
}
