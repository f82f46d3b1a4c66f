package dev.trailprint.app

import android.content.Intent
import android.os.Bundle
import androidx.activity.ComponentActivity
import androidx.activity.compose.BackHandler
import androidx.activity.compose.setContent
import androidx.compose.material3.AlertDialog
import androidx.compose.material3.MaterialTheme
import androidx.compose.material3.Surface
import androidx.compose.material3.Text
import androidx.compose.material3.TextButton
import androidx.compose.runtime.Composable
import androidx.compose.runtime.LaunchedEffect
import androidx.compose.runtime.collectAsState
import androidx.compose.runtime.getValue
import androidx.compose.runtime.mutableStateOf
import androidx.compose.runtime.saveable.rememberSaveable
import androidx.compose.runtime.setValue
import androidx.lifecycle.lifecycleScope
import dev.trailprint.app.survey.SurveyService
import dev.trailprint.app.ui.BuildingsScreen
import dev.trailprint.app.ui.FinishScreen
import dev.trailprint.app.ui.PlanScreen
import dev.trailprint.app.ui.SurveyScreen
import dev.trailprint.app.ui.TeamScreen
import dev.trailprint.app.ui.WalkScreen
import dev.trailprint.app.ui.PastSurveysScreen
import dev.trailprint.files.Destination
import dev.trailprint.files.IncomingRouter
import dev.trailprint.survey.RecordCheck
import dev.trailprint.survey.SurveyMode
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.launch
import kotlinx.coroutines.withContext

/**
 * Hosts the navigation between the screens; each screen has its ViewModel. Files shared to
 * the app are read here and sorted by the host-tested [IncomingRouter]: walk files into
 * the walk inbox, bundles to the team screen, buildings to the buildings screen, anything
 * else refused by name. A survey recorded as active (the app was killed during it) is
 * brought back at launch; a record that cannot be read is offered for forgetting.
 */
class MainActivity : ComponentActivity() {
    private val jump = MutableStateFlow<String?>(null)
    /** A message for the surveyor (refused files, files kept for after the survey). */
    private val notice = MutableStateFlow<String?>(null)
    /** The active-survey record cannot be read: its "Forget" prompt. */
    private val unreadable = MutableStateFlow<RecordCheck.Unreadable?>(null)

    override fun onCreate(savedInstanceState: Bundle?) {
        super.onCreate(savedInstanceState)
        val app = application as TrailprintApp
        if (savedInstanceState == null) {
            when (val r = app.activeSurvey.check()) {
                is RecordCheck.Found -> {
                    SurveyService.restore(this)
                    jump.value = Routes.survey(null, r.survey.mode == SurveyMode.ROBOT)
                }
                is RecordCheck.Unreadable -> unreadable.value = r
                RecordCheck.None -> Unit
            }
            receive(intent)
        }
        setContent {
            MaterialTheme {
                Surface { AppNavigation(jump) }
                val msg by notice.collectAsState()
                msg?.let { m ->
                    AlertDialog(
                        onDismissRequest = { notice.value = null },
                        confirmButton = { TextButton(onClick = { notice.value = null }) { Text("OK") } },
                        text = { Text(m) },
                    )
                }
                val bad by unreadable.collectAsState()
                bad?.let { r ->
                    AlertDialog(
                        onDismissRequest = {},
                        confirmButton = {
                            TextButton(onClick = {
                                unreadable.value = null
                                runCatching { app.activeSurvey.clear() }.onFailure { notice.value = it.message }
                            }) { Text("Forget") }
                        },
                        dismissButton = { TextButton(onClick = { unreadable.value = null }) { Text("Not now") } },
                        title = { Text("The last survey cannot be carried on") },
                        text = { Text(r.prompt) },
                    )
                }
            }
        }
    }

    override fun onNewIntent(intent: Intent) {
        super.onNewIntent(intent)
        receive(intent)
    }

    private fun receive(intent: Intent) {
        val uris = intent.documents()
        if (uris.isEmpty()) return
        val app = application as TrailprintApp
        lifecycleScope.launch {
            val files = withContext(Dispatchers.IO) { uris.map { readIncoming(it) } }
            val surveying = withContext(Dispatchers.IO) { app.activeSurvey.check() is RecordCheck.Found }
            val route = IncomingRouter.route(files, surveyRunning = surveying)
            if (route.walks.isNotEmpty()) app.walks.receive(route.walks.map { it.name to it.text }, ask = !surveying)
            if (route.bundles.isNotEmpty()) app.incomingBundles.value = app.incomingBundles.value + route.bundles
            if (route.buildings.isNotEmpty()) app.incomingBuildings.value = app.incomingBuildings.value + route.buildings
            notice.value = route.message
            when (route.destination) {
                Destination.WALK -> jump.value = Routes.WALK
                Destination.TEAM -> jump.value = Routes.TEAM
                Destination.BUILDINGS -> jump.value = Routes.BUILDINGS
                Destination.STAY -> Unit
            }
        }
    }
}

/** Where the app is: a route string, saved across configuration changes. */
private object Routes {
    const val BUILDINGS = "buildings"
    const val TEAM = "team"
    const val WALK = "walk"
    const val PAST = "past"
    fun plan(buildingId: Long) = "plan/$buildingId"
    /** [planId] null: the survey already running. */
    fun survey(planId: Long?, robot: Boolean) = "survey/${planId ?: "running"}/$robot"
    fun finish(sessionId: Long) = "finish/$sessionId"
}

@Composable
private fun AppNavigation(jump: MutableStateFlow<String?>) {
    var route by rememberSaveable { mutableStateOf(Routes.BUILDINGS) }
    LaunchedEffect(Unit) {
        jump.collect { r -> if (r != null) { route = r; jump.value = null } }
    }
    val parts = route.split('/')
    BackHandler(enabled = route != Routes.BUILDINGS) { route = Routes.BUILDINGS }
    when (parts[0]) {
        "plan" -> PlanScreen(
            buildingId = parts[1].toLong(),
            onStartSurvey = { planId, robot -> route = Routes.survey(planId, robot) },
            onOpenBuilding = { id -> route = Routes.plan(id) },
        )
        "survey" -> SurveyScreen(
            planId = parts[1].toLongOrNull(),
            robot = parts[2].toBoolean(),
            onFinished = { sessionId -> route = Routes.finish(sessionId) },
            rosbridgeUrl = (androidx.compose.ui.platform.LocalContext.current.applicationContext as TrailprintApp).rosbridgeUrl,
        )
        "finish" -> FinishScreen(sessionId = parts[1].toLong(), onDone = { route = Routes.BUILDINGS })
        Routes.TEAM -> TeamScreen()
        Routes.WALK -> WalkScreen(onStart = { planId -> route = Routes.survey(planId, false) }, onBack = { route = Routes.BUILDINGS })
        Routes.PAST -> PastSurveysScreen()
        else -> BuildingsScreen(
            onOpen = { id -> route = Routes.plan(id) },
            onTeam = { route = Routes.TEAM },
            onWalkFiles = { route = Routes.WALK },
            onPastSurveys = { route = Routes.PAST },
        )
    }
}
