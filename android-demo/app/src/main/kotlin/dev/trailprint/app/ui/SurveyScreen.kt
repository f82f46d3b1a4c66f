package dev.trailprint.app.ui

import android.app.Application
import android.content.ComponentName
import android.content.Context
import android.content.Intent
import android.content.ServiceConnection
import android.content.pm.PackageManager
import android.net.Uri
import android.os.Build
import android.os.IBinder
import android.provider.Settings
import androidx.activity.compose.rememberLauncherForActivityResult
import androidx.activity.result.contract.ActivityResultContracts
import androidx.compose.foundation.layout.Arrangement
import androidx.compose.foundation.layout.Column
import androidx.compose.foundation.layout.Row
import androidx.compose.foundation.layout.fillMaxSize
import androidx.compose.foundation.layout.fillMaxWidth
import androidx.compose.foundation.layout.height
import androidx.compose.foundation.layout.padding
import androidx.compose.material3.AlertDialog
import androidx.compose.material3.Button
import androidx.compose.material3.LinearProgressIndicator
import androidx.compose.material3.MaterialTheme
import androidx.compose.material3.OutlinedButton
import androidx.compose.material3.Text
import androidx.compose.material3.TextButton
import androidx.compose.runtime.Composable
import androidx.compose.runtime.DisposableEffect
import androidx.compose.runtime.LaunchedEffect
import androidx.compose.runtime.getValue
import androidx.compose.runtime.mutableStateOf
import androidx.compose.runtime.remember
import androidx.compose.runtime.setValue
import androidx.compose.ui.Modifier
import androidx.compose.ui.platform.LocalContext
import androidx.compose.ui.unit.dp
import androidx.compose.ui.unit.sp
import androidx.core.content.ContextCompat
import androidx.lifecycle.AndroidViewModel
import androidx.lifecycle.compose.collectAsStateWithLifecycle
import androidx.lifecycle.viewModelScope
import androidx.lifecycle.viewmodel.compose.viewModel
import dev.trailprint.app.survey.SurveyService
import dev.trailprint.ffi.Turn
import dev.trailprint.permissions.AppPermission
import dev.trailprint.permissions.PermissionOutcome
import dev.trailprint.permissions.SurveyPermissions
import dev.trailprint.survey.SurveyLifecycle
import dev.trailprint.survey.SurveyMode
import dev.trailprint.ui.SurveyModel
import kotlinx.coroutines.flow.MutableStateFlow

/**
 * The survey screen's ViewModel: binds to [SurveyService], which owns the survey, and
 * exposes its lifecycle; each visit of the screen draws it through a fresh Android-free
 * [SurveyModel]. Unbinding does not stop the survey: the service runs on.
 */
class SurveyViewModel(app: Application) : AndroidViewModel(app) {
    val lifecycle = MutableStateFlow<SurveyLifecycle?>(null)
    private val connection = object : ServiceConnection {
        override fun onServiceConnected(name: ComponentName, binder: IBinder) {
            lifecycle.value = (binder as SurveyService.LocalBinder).service.lifecycle
        }

        override fun onServiceDisconnected(name: ComponentName) {
            lifecycle.value = null
        }
    }

    init {
        app.bindService(Intent(app, SurveyService::class.java), connection, Context.BIND_AUTO_CREATE)
    }

    fun start(planId: Long, mode: SurveyMode, rosbridgeUrl: String?) = SurveyService.start(getApplication(), planId, mode, rosbridgeUrl)

    override fun onCleared() = getApplication<Application>().unbindService(connection)
}

/** The permissions granted now, by manifest name (approximate location included). */
private fun granted(context: Context): Set<String> = SurveyPermissions.checked
    .filter { ContextCompat.checkSelfPermission(context, it) == PackageManager.PERMISSION_GRANTED }.toSet()

private fun arrow(t: Turn?): String = when (t) {
    Turn.LEFT -> "⬅"
    Turn.RIGHT -> "➡"
    Turn.TURN_BACK -> "⬇"
    Turn.CHANGE_FLOOR -> "⇅"
    Turn.ARRIVE -> "⚑"
    else -> "⬆"
}

@Composable
fun SurveyScreen(
    planId: Long?,
    robot: Boolean,
    onFinished: (Long) -> Unit,
    rosbridgeUrl: String? = null,
    vm: SurveyViewModel = viewModel(),
) {
    val context = LocalContext.current
    val mode = if (robot) SurveyMode.ROBOT else SurveyMode.HUMAN
    val lifecycle by vm.lifecycle.collectAsStateWithLifecycle()
    // A fresh model per visit, so the end of an earlier survey is not taken for this one's.
    val bound = remember(lifecycle, planId) { lifecycle?.let { SurveyModel(it, vm.viewModelScope) } }
    DisposableEffect(bound) { onDispose { bound?.close() } }
    var outcome by remember { mutableStateOf<PermissionOutcome?>(null) }
    var asking by remember { mutableStateOf(emptyList<AppPermission>()) }
    fun begin() {
        val o = SurveyPermissions.outcome(mode, Build.VERSION.SDK_INT, granted(context))
        outcome = o
        if (o.canStart && planId != null) vm.start(planId, mode, rosbridgeUrl)
    }
    val permissions = rememberLauncherForActivityResult(ActivityResultContracts.RequestMultiplePermissions()) { begin() }
    // Asked when the survey starts, each with its reason; a survey already running needs no start.
    LaunchedEffect(planId, bound) {
        val m = bound ?: return@LaunchedEffect
        if (planId == null || m.hasActiveSurvey) return@LaunchedEffect
        asking = SurveyPermissions.toAsk(mode, Build.VERSION.SDK_INT, granted(context))
        if (asking.isEmpty()) begin()
    }
    if (asking.isNotEmpty()) {
        AlertDialog(
            onDismissRequest = {},
            confirmButton = { TextButton(onClick = { permissions.launch(SurveyPermissions.request(asking).toTypedArray()); asking = emptyList() }) { Text("Continue") } },
            title = { Text("Before the survey starts") },
            text = { Text(asking.joinToString("\n\n") { it.reason }) },
        )
    }
    outcome?.let { o ->
        val msg = o.blocker ?: return@let
        AlertDialog(
            onDismissRequest = { outcome = null },
            confirmButton = {
                TextButton(onClick = {
                    context.startActivity(Intent(Settings.ACTION_APPLICATION_DETAILS_SETTINGS, Uri.fromParts("package", context.packageName, null)))
                }) { Text("Open settings") }
            },
            dismissButton = {
                // Approximate only: asking again shows Android's "change to precise" dialog.
                if (o.approximateOnly) {
                    TextButton(onClick = { outcome = null; permissions.launch(SurveyPermissions.request(listOf(AppPermission.LOCATION)).toTypedArray()) }) { Text("Allow precise") }
                } else {
                    TextButton(onClick = { outcome = null }) { Text("Not now") }
                }
            },
            title = { Text(if (o.approximateOnly) "Precise location needed" else "Cannot survey") },
            text = { Text(msg) },
        )
    }
    val m = bound
    if (m == null) {
        Text("Connecting to the survey…", Modifier.padding(16.dp))
        return
    }
    val s by m.state.collectAsStateWithLifecycle()
    LaunchedEffect(s.finished) { s.finished?.let { onFinished(it.sessionId) } }
    Column(Modifier.fillMaxSize().padding(12.dp), verticalArrangement = Arrangement.spacedBy(8.dp)) {
        Row(horizontalArrangement = Arrangement.spacedBy(12.dp)) {
            Text(arrow(s.turn), fontSize = 40.sp)
            Column {
                Text(s.instruction, style = MaterialTheme.typography.titleMedium)
                Text("%.0f m to %s".format(s.distanceToNextM, s.nextVertex ?: "the end"))
            }
        }
        if (s.offRoute) Text("Off the planned walk: check in where you are, or replan.", color = MaterialTheme.colorScheme.error)
        s.map?.let { map ->
            MapCanvas(
                map,
                MapOverlay(planned = s.planned, walked = s.walked, estimate = s.estimate, next = s.next),
                Modifier.fillMaxWidth().weight(1f),
                onVertexTap = m::checkInAt,
            )
        }
        LinearProgressIndicator(progress = { s.fraction.toFloat() }, modifier = Modifier.fillMaxWidth())
        Text("%d fingerprints · %s%.1f of %.1f nats".format(s.samples, if (s.collectedIsLowerBound) "≥ " else "", s.collectedNats, s.plannedNats))
        s.scanMessage?.let { Text(it, style = MaterialTheme.typography.bodySmall) }
        s.awakeMessage?.let { Text(it, style = MaterialTheme.typography.bodySmall) }
        (listOfNotNull(s.notice) + outcome?.notes.orEmpty()).forEach { Text(it, style = MaterialTheme.typography.bodySmall) }
        if (!robot) {
            Button(
                onClick = m::checkIn,
                modifier = Modifier.fillMaxWidth().height(88.dp),
            ) { Text(if (s.checkInDue) "CHECK IN at ${s.nextVertex}" else "Check in at ${s.nextVertex ?: "-"}", fontSize = 22.sp) }
        }
        Row(horizontalArrangement = Arrangement.spacedBy(8.dp)) {
            if (s.paused) OutlinedButton(onClick = m::resume) { Text("Resume") }
            else OutlinedButton(onClick = m::pause) { Text("Pause") }
            OutlinedButton(onClick = m::replan, enabled = !s.busy) { Text("Replan") }
            Button(onClick = m::finish) { Text("Finish") }
        }
    }
    s.unreadableRecord?.let { msg ->
        AlertDialog(
            onDismissRequest = {},
            confirmButton = { TextButton(onClick = m::forgetRecord) { Text("Forget") } },
            title = { Text("The last survey cannot be carried on") },
            text = { Text(dev.trailprint.survey.RecordCheck.Unreadable(msg).prompt) },
        )
    }
    s.error?.let { msg ->
        AlertDialog(
            onDismissRequest = m::dismissError,
            confirmButton = { TextButton(onClick = m::dismissError) { Text("OK") } },
            text = { Text(msg) },
        )
    }
}
