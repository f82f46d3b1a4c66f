package dev.trailprint.app.ui

import android.app.Application
import androidx.compose.foundation.layout.Arrangement
import androidx.compose.foundation.layout.Column
import androidx.compose.foundation.layout.Row
import androidx.compose.foundation.layout.fillMaxSize
import androidx.compose.foundation.layout.fillMaxWidth
import androidx.compose.foundation.layout.padding
import androidx.compose.material3.AlertDialog
import androidx.compose.material3.Button
import androidx.compose.material3.FilterChip
import androidx.compose.material3.LinearProgressIndicator
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
import androidx.compose.ui.platform.LocalContext
import androidx.compose.ui.Modifier
import androidx.compose.ui.unit.dp
import androidx.lifecycle.AndroidViewModel
import androidx.lifecycle.compose.collectAsStateWithLifecycle
import androidx.lifecycle.viewModelScope
import androidx.lifecycle.viewmodel.compose.viewModel
import androidx.lifecycle.viewmodel.initializer
import androidx.lifecycle.viewmodel.viewModelFactory
import androidx.lifecycle.ViewModelProvider.AndroidViewModelFactory.Companion.APPLICATION_KEY
import dev.trailprint.app.TrailprintApp
import dev.trailprint.ffi.PlanAlgorithm
import dev.trailprint.geometry.WorldPoint
import dev.trailprint.ui.BudgetUnit
import dev.trailprint.ui.PlanModel
import dev.trailprint.ui.Profile

class PlanViewModel(app: Application, buildingId: Long) : AndroidViewModel(app) {
    val model = PlanModel((app as TrailprintApp).api, viewModelScope, buildingId)

    init {
        model.load()
    }

    companion object {
        fun factory(buildingId: Long) = viewModelFactory {
            initializer { PlanViewModel(this[APPLICATION_KEY]!!, buildingId) }
        }
    }
}

@Composable
fun PlanScreen(
    buildingId: Long,
    onStartSurvey: (planId: Long, robot: Boolean) -> Unit,
    onOpenBuilding: (buildingId: Long) -> Unit,
    vm: PlanViewModel = viewModel(key = "plan-$buildingId", factory = PlanViewModel.factory(buildingId)),
) {
    val s by vm.model.state.collectAsStateWithLifecycle()
    val m = vm.model
    // A part imported after a refusal for memory: plan on it.
    LaunchedEffect(s.partBuilding) {
        s.partBuilding?.let {
            m.partOpened()
            onOpenBuilding(it.id)
        }
    }
    Column(Modifier.fillMaxSize().padding(12.dp), verticalArrangement = Arrangement.spacedBy(8.dp)) {
        Text(s.map?.name ?: "Loading…", style = androidx.compose.material3.MaterialTheme.typography.titleLarge)
        Text("Start: ${s.start ?: "tap a vertex"}   End: ${s.end ?: "tap a vertex"}")
        s.map?.let { map ->
            val byId = map.vertices.associateBy { it.id }
            val planned = s.result?.walk?.mapNotNull { byId[it] }?.map { WorldPoint(it.x, it.y) } ?: emptyList()
            MapCanvas(
                map,
                MapOverlay(planned = planned, highlighted = setOfNotNull(s.start, s.end)),
                Modifier.fillMaxWidth().weight(1f),
                onVertexTap = m::tapVertex,
            )
        }
        Row(horizontalArrangement = Arrangement.spacedBy(8.dp)) {
            OutlinedTextField(
                value = "%.0f".format(s.budget),
                onValueChange = { t -> t.toDoubleOrNull()?.let(m::setBudget) },
                label = { Text("Budget") },
                modifier = Modifier.weight(1f),
            )
            FilterChip(s.unit == BudgetUnit.METRES, { m.setUnit(BudgetUnit.METRES) }, { Text("m") })
            FilterChip(s.unit == BudgetUnit.MINUTES, { m.setUnit(BudgetUnit.MINUTES) }, { Text("min") })
        }
        Row(horizontalArrangement = Arrangement.spacedBy(8.dp)) {
            FilterChip(s.profile == Profile.HUMAN, { m.setProfile(Profile.HUMAN) }, { Text("Walking") })
            FilterChip(s.profile == Profile.ROBOT, { m.setProfile(Profile.ROBOT) }, { Text("Robot") })
        }
        if (s.profile == Profile.ROBOT) {
            val app = LocalContext.current.applicationContext as TrailprintApp
            var url by remember { mutableStateOf(app.rosbridgeUrl ?: "") }
            OutlinedTextField(
                value = url,
                onValueChange = { url = it; app.rosbridgeUrl = it.trim().ifEmpty { null } },
                label = { Text("rosbridge URL (empty: simulated robot)") },
                singleLine = true,
                modifier = Modifier.fillMaxWidth(),
            )
        }
        Row(horizontalArrangement = Arrangement.spacedBy(4.dp)) {
            for (a in listOf(PlanAlgorithm.AUTO, PlanAlgorithm.GREEDY, PlanAlgorithm.GENETIC, PlanAlgorithm.EXACT)) {
                FilterChip(s.algorithm == a, { m.setAlgorithm(a) }, { Text(a.name.lowercase()) })
            }
        }
        if (s.planning) {
            val p = s.progress
            LinearProgressIndicator(progress = { (p?.fraction ?: 0.0).toFloat() }, modifier = Modifier.fillMaxWidth())
            Text(p?.let { "${it.message}  best ${"%.2f".format(it.bestUtilityNats ?: 0.0)} nats" } ?: "Planning…")
            OutlinedButton(onClick = m::cancel) { Text("Cancel") }
        } else {
            s.result?.let { r ->
                Text("%.1f m of %.0f m, %d samples, %.2f nats (%s, %d ms)".format(r.lengthM, r.budgetM, r.samples.toLong(), r.utilityNats, r.algorithm, r.elapsedMs.toLong()))
            }
            Row(horizontalArrangement = Arrangement.spacedBy(8.dp)) {
                Button(onClick = { m.plan() }, enabled = s.canPlan) { Text("Plan") }
                s.result?.let { r ->
                    Button(onClick = { onStartSurvey(r.id, s.profile == Profile.ROBOT) }) { Text("Start survey") }
                }
            }
        }
    }
    s.error?.let { msg ->
        AlertDialog(
            onDismissRequest = m::dismissError,
            confirmButton = {
                val more = s.suggestedTimeLimitS
                val part = s.suggestedPart
                if (more != null) {
                    TextButton(onClick = m::planWithSuggestedTime) { Text("Plan with %.0f s".format(more)) }
                } else if (part != null) {
                    TextButton(onClick = m::planSuggestedPart) { Text("Plan the part within %.0f m".format(part.radiusM)) }
                } else {
                    TextButton(onClick = m::dismissError) { Text("OK") }
                }
            },
            dismissButton = if (s.suggestedTimeLimitS != null || s.suggestedPart != null) {
                { TextButton(onClick = m::dismissError) { Text("Cancel") } }
            } else null,
            title = { Text("Cannot plan") },
            text = { Text(msg) },
        )
    }
}
