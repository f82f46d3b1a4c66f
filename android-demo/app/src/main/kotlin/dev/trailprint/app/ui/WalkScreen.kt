package dev.trailprint.app.ui

import androidx.compose.foundation.clickable
import androidx.compose.foundation.layout.Arrangement
import androidx.compose.foundation.layout.Column
import androidx.compose.foundation.layout.fillMaxSize
import androidx.compose.foundation.layout.fillMaxWidth
import androidx.compose.foundation.layout.padding
import androidx.compose.foundation.rememberScrollState
import androidx.compose.foundation.verticalScroll
import androidx.compose.material3.AlertDialog
import androidx.compose.material3.Button
import androidx.compose.material3.LinearProgressIndicator
import androidx.compose.material3.MaterialTheme
import androidx.compose.material3.OutlinedButton
import androidx.compose.material3.Text
import androidx.compose.material3.TextButton
import androidx.compose.runtime.Composable
import androidx.compose.runtime.LaunchedEffect
import androidx.compose.runtime.getValue
import androidx.compose.ui.Modifier
import androidx.compose.ui.platform.LocalContext
import androidx.compose.ui.unit.dp
import androidx.lifecycle.compose.collectAsStateWithLifecycle
import dev.trailprint.app.TrailprintApp

/**
 * A surveyor's walk files: the app-wide, Android-free [dev.trailprint.team.WalkInboxModel].
 * A file just received is asked about ("Open it as the plan to walk?"); "Later" keeps it
 * "Not opened" in the list, where a tap asks again.
 */
@Composable
fun WalkScreen(onStart: (planId: Long) -> Unit, onBack: () -> Unit) {
    val m = (LocalContext.current.applicationContext as TrailprintApp).walks
    val s by m.state.collectAsStateWithLifecycle()
    LaunchedEffect(Unit) { m.refresh() }
    Column(Modifier.fillMaxSize().padding(16.dp).verticalScroll(rememberScrollState()), verticalArrangement = Arrangement.spacedBy(10.dp)) {
        Text("Your walk", style = MaterialTheme.typography.headlineMedium)
        if (s.busy) LinearProgressIndicator(Modifier.fillMaxWidth())
        s.lines().forEach { Text(it) }
        s.error?.let { Text(it, color = MaterialTheme.colorScheme.error) }
        s.received?.let { r -> Button(onClick = { onStart(r.plan.id) }) { Text("Start this survey") } }
        if (s.inbox.isNotEmpty()) Text("Walk files on this phone", style = MaterialTheme.typography.titleMedium)
        s.inbox.forEach { e ->
            Text(e.line(), Modifier.fillMaxWidth().clickable { m.ask(e) }.padding(vertical = 6.dp))
        }
        OutlinedButton(onClick = onBack) { Text("Back to buildings") }
    }
    s.pendingQuestion()?.let { q ->
        AlertDialog(
            onDismissRequest = m::later,
            confirmButton = { TextButton(onClick = m::openPending) { Text("Open as plan") } },
            dismissButton = { TextButton(onClick = m::later) { Text("Later") } },
            title = { Text("A walk from your coordinator") },
            text = { Text(q) },
        )
    }
}
