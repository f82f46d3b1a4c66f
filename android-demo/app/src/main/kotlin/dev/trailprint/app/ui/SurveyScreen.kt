package dev.trailprint.app.ui

import android.Manifest
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
import androidx.compose.ui.unit.dp
import androidx.compose.ui.unit.sp
import androidx.lifecycle.AndroidViewModel
import androidx.lifecycle.ViewModelProvider.AndroidViewModelFactory.Companion.APPLICATION_KEY
import androidx.lifecycle.compose.collectAsStateWithLifecycle
import androidx.lifecycle.viewModelScope
import androidx.lifecycle.viewmodel.compose.viewModel
import androidx.lifecycle.viewmodel.initializer
import androidx.lifecycle.viewmodel.viewModelFactory
import dev.trailprint.app.TrailprintApp
import dev.trailprint.app.sensors.AndroidStepSource
import dev.trailprint.app.sensors.AndroidWifiScanSource
import dev.trailprint.app.sensors.OkHttpWebSocketFactory
import dev.trailprint.ffi.Position
import dev.trailprint.ffi.Turn
import dev.trailprint.ffi.defaultHumanProfile
import dev.trailprint.ffi.defaultRobotProfile
import dev.trailprint.robot.RobotDriver
import dev.trailprint.robot.RobotException
import dev.trailprint.robot.RosbridgeConfig
import dev.trailprint.robot.RosbridgeRobotDriver
import dev.trailprint.robot.SimulatedRobot
import dev.trailprint.robot.SimulatedRobotConfig
import dev.trailprint.ui.SurveyModel
import kotlinx.coroutines.launch

/**
 * The survey screen's ViewModel: the Android-free [SurveyModel] on viewModelScope, plus the
 * sensor glue — the phone's steps and Wi-Fi scans for a person, or a robot driver (the
 * simulated robot, or a ROS 2 robot through rosbridge when [rosbridgeUrl] is given) and the
 * phone's Wi-Fi scans for a robot.
 */
class SurveyViewModel(app: Application, private val planId: Long, private val robot: Boolean, private val rosbridgeUrl: String?) : AndroidViewModel(app) {
    val model = SurveyModel((app as TrailprintApp).api, viewModelScope)
    private val wifi = AndroidWifiScanSource(app)
    private var driver: RobotDriver? = null

    fun start() {
        val profile = if (robot) defaultRobotProfile() else defaultHumanProfile()
        model.start(planId, profile) { controller, map ->
            if (robot) startRobot(controller, map) else controller.attachHumanSensors(AndroidStepSource(getApplication()), wifi)
        }
    }

    private fun startRobot(controller: dev.trailprint.survey.SurveyController, map: dev.trailprint.ffi.BuildingMap) {
        val d = rosbridgeUrl?.let { RosbridgeRobotDriver(OkHttpWebSocketFactory(), RosbridgeConfig(url = it)) }
            ?: SimulatedRobot(SimulatedRobotConfig(speed = 0.5))
        driver = d
        controller.attachRobot(d, wifi)
        val pos = map.vertices.associate { it.id to Position(it.x, it.y, it.floor) }
        viewModelScope.launch {
            try {
                d.follow(controller.waypointsAhead(pos))
            } catch (e: RobotException) {
                model.reportError("Robot: ${e.message}")
            }
        }
    }

    override fun onCleared() {
        driver?.close()
        model.controller?.stopSensors()
    }

    companion object {
        fun factory(planId: Long, robot: Boolean, rosbridgeUrl: String?) = viewModelFactory {
            initializer { SurveyViewModel(this[APPLICATION_KEY]!!, planId, robot, rosbridgeUrl) }
        }
    }
}

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
    planId: Long,
    robot: Boolean,
    onFinished: (Long) -> Unit,
    rosbridgeUrl: String? = null,
    vm: SurveyViewModel = viewModel(key = "survey-$planId", factory = SurveyViewModel.factory(planId, robot, rosbridgeUrl)),
) {
    val s by vm.model.state.collectAsStateWithLifecycle()
    val permissions = rememberLauncherForActivityResult(ActivityResultContracts.RequestMultiplePermissions()) { vm.start() }
    LaunchedEffect(planId) {
        permissions.launch(arrayOf(Manifest.permission.ACCESS_FINE_LOCATION, Manifest.permission.ACTIVITY_RECOGNITION))
    }
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
                onVertexTap = vm.model::checkInAt,
            )
        }
        LinearProgressIndicator(progress = { s.fraction.toFloat() }, modifier = Modifier.fillMaxWidth())
        Text("%d fingerprints · %.1f of %.1f nats".format(s.samples, s.collectedNats, s.plannedNats))
        s.scanMessage?.let { Text(it, style = MaterialTheme.typography.bodySmall) }
        if (!robot) {
            Button(
                onClick = vm.model::checkIn,
                modifier = Modifier.fillMaxWidth().height(88.dp),
            ) { Text(if (s.checkInDue) "CHECK IN at ${s.nextVertex}" else "Check in at ${s.nextVertex ?: "-"}", fontSize = 22.sp) }
        }
        Row(horizontalArrangement = Arrangement.spacedBy(8.dp)) {
            if (s.paused) OutlinedButton(onClick = vm.model::resume) { Text("Resume") }
            else OutlinedButton(onClick = vm.model::pause) { Text("Pause") }
            OutlinedButton(onClick = vm.model::replan, enabled = !s.busy) { Text("Replan") }
            Button(onClick = vm.model::finish) { Text("Finish") }
        }
    }
    s.error?.let { msg ->
        AlertDialog(
            onDismissRequest = vm.model::dismissError,
            confirmButton = { TextButton(onClick = vm.model::dismissError) { Text("OK") } },
            text = { Text(msg) },
        )
    }
}
